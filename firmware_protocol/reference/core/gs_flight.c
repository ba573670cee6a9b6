/* See gs_flight.h. The numbers follow groundstation/sim/firmware.py (Firmware._run_block, command)
 * to the bit: conversions in double as groundstation/units.py does them, then rounded to float. */
#include "gs_flight.h"

#include <math.h>
#include <string.h>

#define GS_PI 3.14159265358979323846

/* Datasheet sensitivities (MPU-6000/6050 Product Specification rev 3.4, tables 6.1, 6.2), as in
 * groundstation/units.py: the gyro's are the rounded 131, 65.5, 32.8 and 16.4 LSB/(deg/s). */
static double accel_lsb_per_g(unsigned fs_g)
{
    switch (fs_g) {
    case 2: return 16384.0;
    case 4: return 8192.0;
    case 8: return 4096.0;
    case 16: return 2048.0;
    default: return 0.0;
    }
}

static double gyro_lsb_per_dps(unsigned fs_dps)
{
    switch (fs_dps) {
    case 250: return 131.0;
    case 500: return 65.5;
    case 1000: return 32.8;
    case 2000: return 16.4;
    default: return 0.0;
    }
}

/* groundstation/mounting.py's numbering: the forward axis runs through +x -x +y -y +z -z, and for
 * each the right axis through the same list, skipping the two parallel to forward; down = f x r. */
static int mounting_matrix(unsigned index, signed char m[3][3])
{
    unsigned n = 0;
    for (int fwd = 0; fwd < 6; fwd++) {
        for (int right = 0; right < 6; right++) {
            if (right / 2 == fwd / 2) continue;
            if (n++ != index) continue;
            signed char fv[3] = {0, 0, 0}, rv[3] = {0, 0, 0};
            fv[fwd / 2] = (signed char)(fwd % 2 ? -1 : 1);
            rv[right / 2] = (signed char)(right % 2 ? -1 : 1);
            for (int i = 0; i < 3; i++) {
                m[0][i] = fv[i];
                m[1][i] = rv[i];
            }
            m[2][0] = (signed char)(fv[1] * rv[2] - fv[2] * rv[1]);
            m[2][1] = (signed char)(fv[2] * rv[0] - fv[0] * rv[2]);
            m[2][2] = (signed char)(fv[0] * rv[1] - fv[1] * rv[0]);
            return 0;
        }
    }
    return -1;
}

/* Python's round(): to the nearest integer, ties to even (rint in the default rounding mode). */
static long round_even(double x) { return (long)rint(x); }

/* codec.make_scaled_frame: raw = floor(value / scale + 0.5), saturated to [low, high]. */
static long scaled(double value, double scale, long low, long high)
{
    double raw = floor(value / scale + 0.5);
    return raw < (double)low ? low : raw > (double)high ? high : (long)raw;
}

static uint8_t *queue_slot(gs_flight *f) { return f->queued < GS_FLIGHT_QUEUE ? f->queue[f->queued++] : NULL; }

static void queue_config(gs_flight *f)
{
    uint8_t *slot = queue_slot(f);
    if (slot == NULL) return;
    gs_config_t m = {
        .protocol_version = GS_PROTOCOL_VERSION, .schema_fingerprint = GS_SCHEMA_FINGERPRINT,
        .fw_major = f->cfg.fw_version[0], .fw_minor = f->cfg.fw_version[1], .fw_patch = f->cfg.fw_version[2],
        .accel_fs_g = f->cfg.accel_fs_g, .gyro_fs_dps = f->cfg.gyro_fs_dps, .rate_hz = f->cfg.rate_hz,
        .mode = f->mode, .mounting = f->cfg.mounting, .gyro_calibration = f->gyro_calibration,
    };
    gs_pack_config(slot, 0, &m); /* seq and CRC are rewritten when it is sent */
}

static void start_calibration(gs_flight *f, double seconds)
{
    long n = round_even(seconds * f->cfg.rate_hz);
    f->calibration_n = f->calibration_left = (uint32_t)(n < 1 ? 1 : n);
    f->calibration_sum_dps[0] = f->calibration_sum_dps[1] = f->calibration_sum_dps[2] = 0.0;
    memset(f->calibration_counts, 0, sizeof f->calibration_counts);
}

/* Whether n samples of three axes with these count sums and sums of squares deviate from their mean
 * by at most limit RMS (per_count counts a unit): sum over the axes of n Sxx - Sx^2 = n^2 x the
 * summed variance, in double in this order, as firmware.py's within_rms. */
static int within_rms(uint32_t n, const int64_t sums[3], const int64_t squares[3], double per_count, double limit)
{
    double spread = 0.0;
    for (int i = 0; i < 3; i++) spread += (double)n * (double)squares[i] - (double)sums[i] * (double)sums[i];
    double bound = limit * per_count * (double)n;
    return spread <= bound * bound;
}

static int calibration_still(const gs_flight *f)
{
    const int64_t (*c)[3] = f->calibration_counts;
    return within_rms(f->calibration_n, c[0], c[1], f->gyro_lsb_per_dps, GS_FLIGHT_STILL_GYRO_RMS_DPS)
        && within_rms(f->calibration_n, c[2], c[3], f->accel_lsb_per_g, GS_FLIGHT_STILL_ACCEL_RMS_G);
}

int gs_flight_init(gs_flight *f, const gs_flight_config *cfg)
{
    memset(f, 0, sizeof *f);
    f->cfg = *cfg;
    f->accel_lsb_per_g = accel_lsb_per_g(cfg->accel_fs_g);
    f->gyro_lsb_per_dps = gyro_lsb_per_dps(cfg->gyro_fs_dps);
    if (f->accel_lsb_per_g == 0.0 || f->gyro_lsb_per_dps == 0.0 || cfg->rate_hz == 0 || cfg->mode > GS_MODE_BOTH
        || mounting_matrix(cfg->mounting, f->body) != 0 || gs_ahf_init(&f->ahf, &cfg->ahf, NULL) != 0) {
        return -1;
    }
    f->mode = cfg->mode;
    f->gyro_calibration = (uint8_t)GS_GYRO_CALIBRATION_NONE;
    f->nominal_period_us = (uint32_t)round_even(1.0 / cfg->rate_hz * 1e6);
    f->booting = 1;
    if (cfg->boot_calibration_s > 0.0) {
        start_calibration(f, cfg->boot_calibration_s);
    } else { /* a board that skips it streams its turn-on gyro bias */
        f->booting = 0;
        queue_config(f);
    }
    return 0;
}

void gs_flight_restore_gyro_offset(gs_flight *f, const double offset_dps[3])
{
    for (int i = 0; i < 3; i++) f->stored_offset_dps[i] = offset_dps[i];
    f->have_stored_offset = 1;
}

static void finish_calibration(gs_flight *f)
{
    /* a commanded one is trusted: the user was told to keep the craft still */
    if (!f->booting || calibration_still(f)) {
        for (int i = 0; i < 3; i++) f->offset_dps[i] += f->calibration_sum_dps[i] / f->calibration_n;
        f->offset_ready = 1;
        f->gyro_calibration = (uint8_t)(f->booting ? GS_GYRO_CALIBRATION_BOOT : GS_GYRO_CALIBRATION_COMMAND);
    } else if (f->have_stored_offset) { /* moving at boot: the registers are 0, write the stored one */
        for (int i = 0; i < 3; i++) f->offset_dps[i] = f->stored_offset_dps[i];
        f->offset_ready = 1;
        f->gyro_calibration = (uint8_t)GS_GYRO_CALIBRATION_STORED;
    }
    f->calibration_n = 0;
    if (f->booting) {
        f->booting = 0;
        queue_config(f);
    }
}

int gs_flight_take_gyro_offset(gs_flight *f, double offset_dps[3])
{
    if (!f->offset_ready) return 0;
    for (int i = 0; i < 3; i++) {
        offset_dps[i] = f->offset_dps[i];
        f->offset_dps[i] = 0.0;
    }
    f->offset_ready = 0;
    return 1;
}

/* Counts on the sensor axes, converted in double as units.py does (counts / sensitivity, then times
 * unit; 1.0 for g), onto the body axes, rounded to float. */
static void to_body(const gs_flight *f, const int16_t counts[3], double per_count, double unit, float out[3])
{
    double v[3];
    for (int i = 0; i < 3; i++) v[i] = (double)counts[i] / per_count * unit;
    for (int i = 0; i < 3; i++) out[i] = (float)(v[0] * f->body[i][0] + v[1] * f->body[i][1] + v[2] * f->body[i][2]);
}

static size_t emit(gs_flight *f, uint8_t *out, size_t cap, size_t n, uint8_t *frame)
{
    size_t len = gs_finish_frame(frame, frame[2], f->seq, frame[1]);
    if (n + len > cap) return n;
    if (frame != out + n) memcpy(out + n, frame, len);
    f->seq = (uint8_t)(f->seq + 1u);
    return n + len;
}

size_t gs_flight_sample(gs_flight *f, const gs_sample *s, uint8_t *out, size_t cap)
{
    uint8_t frame[GS_MAX_FRAME_BYTES];
    size_t n = 0;
    uint32_t k = f->k++;
    if (f->calibration_n) {
        for (int i = 0; i < 3; i++) {
            f->calibration_sum_dps[i] += (double)s->gyr[i] / f->gyro_lsb_per_dps;
            f->calibration_counts[0][i] += s->gyr[i];
            f->calibration_counts[1][i] += (int64_t)s->gyr[i] * s->gyr[i];
            f->calibration_counts[2][i] += s->acc[i];
            f->calibration_counts[3][i] += (int64_t)s->acc[i] * s->acc[i];
        }
    }
    if (!f->booting) {
        for (unsigned i = 0; i < f->queued; i++) n = emit(f, out, cap, n, f->queue[i]);
        f->queued = 0;

        float gyr[3], acc[3];
        to_body(f, s->gyr, f->gyro_lsb_per_dps, GS_PI / 180.0, gyr);
        to_body(f, s->acc, f->accel_lsb_per_g, 1.0, acc);
        /* The filter starts with the stream: its first dt is the nominal period, as a host assumes. */
        uint32_t prev = f->ahf_stepped ? f->last_t_us : s->t_us - f->nominal_period_us;
        float dt_s = (float)((double)(int32_t)(s->t_us - prev) * 1e-6);
        f->last_t_us = s->t_us;
        unsigned status = gs_ahf_step(&f->ahf, gyr, acc, dt_s);
        f->ahf_stepped = 1;

        if (k % f->cfg.rate_hz == 0) {
            gs_status_t m = {
                .t_us = s->t_us,
                .battery = (uint16_t)scaled(s->battery_v, GS_SCALE_STATUS_BATTERY, 0, 65535),
                .retransmits = s->retransmits,
                .lost_acks = s->lost_acks,
                .cpu_load = (uint8_t)scaled(s->cpu_load_pct, GS_SCALE_STATUS_CPU_LOAD, 0, 255),
                .flags = (uint16_t)((f->calibration_n ? GS_STATUS_CALIBRATING : 0u)
                                    | (s->battery_v < GS_FLIGHT_LOW_BATTERY_V ? GS_STATUS_LOW_BATTERY : 0u) | s->port_flags),
            };
            gs_pack_status(frame, 0, &m);
            n = emit(f, out, cap, n, frame);
        }
        if (f->mode != GS_MODE_ESTIMATED) {
            gs_imu_raw_t m = {
                .t_us = s->t_us,
                .acc_x = s->acc[0], .acc_y = s->acc[1], .acc_z = s->acc[2],
                .gyr_x = s->gyr[0], .gyr_y = s->gyr[1], .gyr_z = s->gyr[2],
                /* the die temperature as groundstation/units.py converts TEMP_OUT: counts / 340 + 36.53 degC */
                .temperature = (int16_t)round_even(((double)s->temperature / 340.0 + 36.53) * (1.0 / GS_SCALE_IMU_RAW_TEMPERATURE)),
            };
            gs_pack_imu_raw(frame, 0, &m);
            n = emit(f, out, cap, n, frame);
        }
        if (f->mode != GS_MODE_RAW) {
            int16_t q[4];
            for (int i = 0; i < 4; i++) {
                long v = round_even((double)f->ahf.q[i] * (1.0 / GS_SCALE_ATTITUDE_Q_W));
                q[i] = (int16_t)(v < -32768 ? -32768 : v > 32767 ? 32767 : v);
            }
            double lam = (double)f->ahf.lam * (1.0 / GS_SCALE_ATTITUDE_LAMBDA_GAIN);
            gs_attitude_t m = {
                .t_us = s->t_us, .q_w = q[0], .q_x = q[1], .q_y = q[2], .q_z = q[3],
                .lambda_gain = (uint16_t)(lam >= 65535.0 ? 65535 : round_even(lam)),
                .flags = (uint8_t)(((status & (GS_AHF_WAITING | GS_AHF_INITIALISED)) ? 1u : 0u)
                                   | ((status & GS_AHF_GYRO_OVERRANGE) ? 2u : 0u) | ((status & GS_AHF_ACC_SKIPPED) ? 4u : 0u)),
            };
            gs_pack_attitude(frame, 0, &m);
            n = emit(f, out, cap, n, frame);
        }
    }
    if (f->calibration_n && --f->calibration_left == 0) finish_calibration(f);
    return n;
}

static uint8_t set_filter_param(gs_flight *f, uint8_t param, double value)
{
    if (!isfinite(value)) return GS_ACK_RESULT_BAD_VALUE;
    gs_ahf_settings s = f->ahf.settings;
    switch (param) {
    case GS_FILTER_PARAM_LAMBDA_MAX: s.lambda_max = value; break;
    case GS_FILTER_PARAM_LAMBDA_MIN: s.lambda_min = value; break;
    case GS_FILTER_PARAM_LOWPASS: s.lowpass = value; break;
    case GS_FILTER_PARAM_ERROR_GAIN: s.error_gain = value; break;
    case GS_FILTER_PARAM_GYRO_OVERRANGE: s.gyro_overrange_rad_s = value > 0.0 ? value : HUGE_VAL; break;
    default: return GS_ACK_RESULT_BAD_VALUE;
    }
    gs_ahf fresh;
    /* Keep the attitude: a tuning change must not make the estimate jump. */
    if (gs_ahf_init(&fresh, &s, f->ahf_stepped ? f->ahf.q : NULL) != 0) return GS_ACK_RESULT_BAD_VALUE;
    f->ahf = fresh;
    return GS_ACK_RESULT_OK;
}

void gs_flight_uplink(gs_flight *f, const uint8_t *frame, size_t len)
{
    if (gs_check_frame(frame, len) < 0 || frame[2] != GS_ID_COMMAND || f->queued + 2u > GS_FLIGHT_QUEUE) return;
    gs_command_t c;
    gs_unpack_command(frame + GS_HEADER_BYTES, &c);
    uint8_t result = GS_ACK_RESULT_OK;
    int follow_config = 0;
    switch (c.command) {
    case GS_COMMAND_SET_MODE:
        if (c.param <= GS_MODE_BOTH) {
            f->mode = c.param;
            follow_config = 1;
        } else {
            result = GS_ACK_RESULT_BAD_VALUE;
        }
        break;
    case GS_COMMAND_SET_FILTER_PARAM:
        result = set_filter_param(f, c.param, (double)c.value);
        break;
    case GS_COMMAND_REQUEST_CONFIG:
        follow_config = 1;
        break;
    case GS_COMMAND_CALIBRATE_GYRO: {
        /* averaging time in s, 0 -> 1 s; the craft must be at rest */
        double seconds = c.value > 0.0f ? (double)c.value : 1.0;
        if (f->calibration_n) {
            result = GS_ACK_RESULT_BUSY;
        } else if (!(seconds <= GS_FLIGHT_MAX_CALIBRATION_S)) {
            result = GS_ACK_RESULT_BAD_VALUE;
        } else {
            start_calibration(f, seconds);
        }
        break;
    }
    default:
        result = GS_ACK_RESULT_UNSUPPORTED;
    }
    gs_ack_t ack = {.command_seq = frame[3], .command = c.command, .result = result};
    gs_pack_ack(queue_slot(f), 0, &ack);
    if (follow_config) queue_config(f);
}
