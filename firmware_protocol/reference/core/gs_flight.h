/* The flight board's firmware logic, with no hardware in it: MPU-6050 registers in, frames out.
 *
 * The board port reads the MPU-6050 at the output rate and hands each sample (register counts, its
 * microsecond timestamp, the battery voltage, the radio's counters) to gs_flight_sample(), which
 * returns the frames to send, each a whole nRF24L01+ payload; uplink payloads go to gs_flight_uplink().
 * What it does is what groundstation/sim/firmware.py models, frame for frame:
 *
 * - boot: the first boot_calibration_s of samples average the gyro; if the craft was still over them
 *   (GS_FLIGHT_STILL_*) the port writes the average into the chip's offset registers
 *   (gs_flight_take_gyro_offset), else the last calibration the port keeps over resets (gs_flight_restore_gyro_offset),
 *   if any; CONFIG.gyro_calibration says which, and CONFIG goes out;
 * - each sample: the onboard AHF (gs_ahf.h) steps; IMU_RAW (mode raw or both) and ATTITUDE (estimated
 *   or both); STATUS every rate_hz samples, counted from power-up;
 * - COMMAND: set_mode, set_filter_param, request_config, calibrate_gyro, each answered with ACK (and
 *   CONFIG after set_mode and request_config) before the next sample's frames.
 *
 * One sequence counter numbers every frame sent. Built only on the generated gs_protocol.h. */
#ifndef GS_FLIGHT_H
#define GS_FLIGHT_H

#include <stddef.h>
#include <stdint.h>

#include "gs_ahf.h"
#include "gs_protocol.h"

/* Frames waiting for the next sample (ACK, CONFIG); a command that finds no room is ignored. */
#define GS_FLIGHT_QUEUE 6u
/* The most bytes one gs_flight_sample() returns: the queue, STATUS, IMU_RAW and ATTITUDE. */
#define GS_FLIGHT_MAX_OUT ((GS_FLIGHT_QUEUE + 3u) * GS_MAX_FRAME_BYTES)
/* Below this the STATUS low-battery flag is set: a 3S LiPo at 3.6 V a cell. */
#define GS_FLIGHT_LOW_BATTERY_V 10.8
/* The longest gyro calibration a command may ask for. */
#define GS_FLIGHT_MAX_CALIBRATION_S 60.0

/* Still enough for the boot calibration to be used: the RMS deviation from the window's mean of the
 * gyro (deg/s) and of the accelerometer (g), the three axes together. The same numbers as
 * groundstation/sim/firmware.py (STILL_GYRO_RMS_DPS, STILL_ACCEL_RMS_G). */
#define GS_FLIGHT_STILL_GYRO_RMS_DPS 0.5
#define GS_FLIGHT_STILL_ACCEL_RMS_G 0.03

/* STATUS.flags bits */
#define GS_STATUS_CALIBRATING 1u
#define GS_STATUS_LOW_BATTERY 2u
#define GS_STATUS_IMU_ERROR 4u
#define GS_STATUS_TX_OVERFLOW 8u

typedef struct {
    uint16_t rate_hz;         /* output rate: one gs_flight_sample() per 1/rate_hz s */
    uint8_t accel_fs_g;       /* 2, 4, 8, 16: as written to ACCEL_CONFIG */
    uint16_t gyro_fs_dps;     /* 250, 500, 1000, 2000: as written to GYRO_CONFIG */
    uint8_t mounting;         /* 0-23, groundstation/mounting.py's numbering */
    uint8_t mode;             /* GS_MODE_* at power-up */
    double boot_calibration_s; /* gyro averaging before streaming; 0 = none */
    uint8_t fw_version[3];    /* major, minor, patch, reported in CONFIG */
    gs_ahf_settings ahf;
} gs_flight_config;

typedef struct {
    uint32_t t_us;            /* device time the registers were read, microseconds (wraps) */
    int16_t acc[3];           /* ACCEL_XOUT..ZOUT, sensor axes */
    int16_t gyr[3];           /* GYRO_XOUT..ZOUT */
    int16_t temperature;      /* TEMP_OUT */
    double battery_v;         /* measured battery voltage */
    double cpu_load_pct;      /* share of the last second the CPU was busy */
    uint16_t retransmits;     /* radio auto-retransmissions in the last second */
    uint16_t lost_acks;       /* payloads the radio gave up on in the last second */
    uint16_t port_flags;      /* GS_STATUS_IMU_ERROR, GS_STATUS_TX_OVERFLOW as the port sees them */
} gs_sample;

typedef struct {
    gs_flight_config cfg;
    gs_ahf ahf;
    int ahf_stepped;          /* the AHF has had a sample (a new setting keeps its attitude) */
    uint8_t mode;
    uint8_t seq;
    uint32_t k;               /* samples since power-up */
    int booting;
    uint32_t calibration_left; /* samples still to average; 0 = not calibrating */
    uint32_t calibration_n;
    double calibration_sum_dps[3];
    int64_t calibration_counts[4][3]; /* sums of gyro counts, their squares, accel counts, their squares */
    int have_stored_offset;
    double stored_offset_dps[3];  /* the last calibration, kept over resets (gs_flight_restore_gyro_offset) */
    uint8_t gyro_calibration; /* GS_GYRO_CALIBRATION_*: where the offsets in use came from (CONFIG) */
    int offset_ready;
    double offset_dps[3];     /* to add to the chip's gyro offset, deg/s (gs_flight_take_gyro_offset) */
    uint32_t last_t_us;
    uint32_t nominal_period_us;
    double accel_lsb_per_g, gyro_lsb_per_dps;
    signed char body[3][3];   /* v_body = body * v_sensor */
    uint8_t queue[GS_FLIGHT_QUEUE][GS_MAX_FRAME_BYTES];
    unsigned queued;
} gs_flight;

/* Returns 0, or -1 for an invalid configuration (full scale, mounting, mode, rate, AHF settings). */
int gs_flight_init(gs_flight *f, const gs_flight_config *cfg);

/* One sample. Writes the frames to send (each one payload, back to back) into out, at most cap
 * bytes (GS_FLIGHT_MAX_OUT is always enough); returns the number of bytes written. */
size_t gs_flight_sample(gs_flight *f, const gs_sample *s, uint8_t *out, size_t cap);

/* One uplink payload (a whole frame). Only intact COMMAND frames act. */
void gs_flight_uplink(gs_flight *f, const uint8_t *frame, size_t len);

/* 1 when a gyro calibration has finished since the last call: offset_dps (deg/s, sensor axes) is to
 * be subtracted from what the chip reports (added to its offset registers) before the next sample.
 * What the registers then hold (they start at 0 at power-up) is the calibration to keep over resets. */
int gs_flight_take_gyro_offset(gs_flight *f, double offset_dps[3]);

/* At power-up, before the first sample: the calibration kept over resets (deg/s, sensor axes), written
 * to the registers if the craft moves during the boot calibration. */
void gs_flight_restore_gyro_offset(gs_flight *f, const double offset_dps[3]);

/* The length of the frame at p (header byte 1 + header and CRC). */
static inline size_t gs_frame_length(const uint8_t *p) { return (size_t)p[1] + GS_HEADER_BYTES + GS_CRC_BYTES; }

#endif /* GS_FLIGHT_H */
