/* The core's entry points with plain arguments, for the host: Python's ctypes (groundstation's
 * firmware-in-the-loop and the tests) needs no copy of the C structs' layout. Not built for a board. */
#include <stddef.h>
#include <stdint.h>

#include "gs_ahf.h"
#include "gs_deframer.h"
#include "gs_flight.h"

size_t gs_host_sizeof_ahf(void) { return sizeof(gs_ahf); }
size_t gs_host_sizeof_flight(void) { return sizeof(gs_flight); }
size_t gs_host_sizeof_deframer(void) { return sizeof(gs_deframer); }
size_t gs_host_max_out(void) { return GS_FLIGHT_MAX_OUT; }

/* settings: lambda_max, lambda_min, lowpass, error_gain, gyro_overrange_rad_s, acc_min_g, acc_deviation_max_g,
 * acc_window_s, max_gap_s */
static void ahf_settings(gs_ahf_settings *s, const double v[9])
{
    s->lambda_max = v[0];
    s->lambda_min = v[1];
    s->lowpass = v[2];
    s->error_gain = v[3];
    s->gyro_overrange_rad_s = v[4];
    s->acc_min_g = v[5];
    s->acc_deviation_max_g = v[6];
    s->acc_window_s = v[7];
    s->max_gap_s = v[8];
}

int gs_host_ahf_init(gs_ahf *f, const double settings[9], const float *q0)
{
    gs_ahf_settings s;
    ahf_settings(&s, settings);
    return gs_ahf_init(f, &s, q0);
}

/* out: q (4), lambda, e_a, err, acc_dev */
unsigned gs_host_ahf_step(gs_ahf *f, const float gyr[3], const float acc[3], float dt_s, float out[8])
{
    unsigned status = gs_ahf_step(f, gyr, acc, dt_s);
    for (int i = 0; i < 4; i++) out[i] = f->q[i];
    out[4] = f->lam;
    out[5] = f->e_a;
    out[6] = f->err;
    out[7] = f->acc_dev;
    return status;
}

/* config: rate_hz, accel_fs_g, gyro_fs_dps, mounting, mode, fw major, minor, patch */
int gs_host_flight_init(gs_flight *f, const unsigned config[8], double boot_calibration_s, const double settings[9])
{
    gs_flight_config c = {
        .rate_hz = (uint16_t)config[0], .accel_fs_g = (uint8_t)config[1], .gyro_fs_dps = (uint16_t)config[2],
        .mounting = (uint8_t)config[3], .mode = (uint8_t)config[4], .boot_calibration_s = boot_calibration_s,
        .fw_version = {(uint8_t)config[5], (uint8_t)config[6], (uint8_t)config[7]},
    };
    ahf_settings(&c.ahf, settings);
    return gs_flight_init(f, &c);
}

/* registers: acc x y z, gyr x y z, temperature; status: battery_v, cpu_load_pct */
size_t gs_host_flight_sample(gs_flight *f, uint32_t t_us, const int16_t registers[7], const double status[2], uint8_t *out, size_t cap)
{
    gs_sample s = {.t_us = t_us, .temperature = registers[6], .battery_v = status[0], .cpu_load_pct = status[1]};
    for (int i = 0; i < 3; i++) {
        s.acc[i] = registers[i];
        s.gyr[i] = registers[3 + i];
    }
    return gs_flight_sample(f, &s, out, cap);
}

void gs_host_flight_uplink(gs_flight *f, const uint8_t *frame, size_t len) { gs_flight_uplink(f, frame, len); }
int gs_host_flight_take_gyro_offset(gs_flight *f, double offset_dps[3]) { return gs_flight_take_gyro_offset(f, offset_dps); }
void gs_host_flight_restore_gyro_offset(gs_flight *f, const double offset_dps[3]) { gs_flight_restore_gyro_offset(f, offset_dps); }
unsigned gs_host_flight_mode(const gs_flight *f) { return f->mode; }
int gs_host_flight_booting(const gs_flight *f) { return f->booting; }
void gs_host_deframer_init(gs_deframer *d) { gs_deframer_init(d); }

/* Pushes len bytes; writes each complete frame to out (back to back); returns the bytes written. */
size_t gs_host_deframer_feed(gs_deframer *d, const uint8_t *data, size_t len, uint8_t *out, size_t cap)
{
    size_t n = 0;
    for (size_t i = 0; i < len; i++) {
        size_t frame = gs_deframer_push(d, data[i]);
        if (frame && n + frame <= cap) {
            for (size_t j = 0; j < frame; j++) out[n + j] = d->buf[j];
            n += frame;
        }
    }
    return n;
}
