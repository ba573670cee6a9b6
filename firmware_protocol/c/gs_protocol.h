/* Generated from firmware_protocol/spec.toml by `python -m firmware_protocol.generate`. Do not edit. */
/* Telemetry frames for the nRF24L01 link: sync | length | type | seq | payload | crc16 (see docs/protocol.md). */
#ifndef GS_PROTOCOL_H
#define GS_PROTOCOL_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define GS_PROTOCOL_VERSION 1u
#define GS_SCHEMA_FINGERPRINT 0xA6FC8BE6u
#define GS_SYNC 0xA5u
#define GS_MAX_FRAME_BYTES 32u
#define GS_HEADER_BYTES 4u
#define GS_CRC_BYTES 2u

/* mode: What the aircraft sends at the output rate. */
#define GS_MODE_RAW 0u
#define GS_MODE_ESTIMATED 1u
#define GS_MODE_BOTH 2u

/* command: COMMAND.command: what the ground asks the aircraft to do. */
#define GS_COMMAND_SET_MODE 1u
#define GS_COMMAND_SET_FILTER_PARAM 2u
#define GS_COMMAND_REQUEST_CONFIG 3u
#define GS_COMMAND_CALIBRATE_GYRO 4u

/* filter_param: COMMAND.param for set_filter_param: which onboard AHF setting (seed 000 eq. 20) to change. */
#define GS_FILTER_PARAM_LAMBDA_MAX 0u
#define GS_FILTER_PARAM_LAMBDA_MIN 1u
#define GS_FILTER_PARAM_LOWPASS 2u
#define GS_FILTER_PARAM_ERROR_GAIN 3u
#define GS_FILTER_PARAM_GYRO_OVERRANGE 4u

/* ack_result: ACK.result. */
#define GS_ACK_RESULT_OK 0u
#define GS_ACK_RESULT_UNSUPPORTED 1u
#define GS_ACK_RESULT_BAD_VALUE 2u
#define GS_ACK_RESULT_BUSY 3u
#define GS_ACK_RESULT_FAILED 4u

/* gyro_calibration: CONFIG.gyro_calibration: where the gyro offsets the aircraft uses now came from. */
#define GS_GYRO_CALIBRATION_NONE 0u
#define GS_GYRO_CALIBRATION_BOOT 1u
#define GS_GYRO_CALIBRATION_STORED 2u
#define GS_GYRO_CALIBRATION_COMMAND 3u

/* gps_fix: GPS.fix_type. */
#define GS_GPS_FIX_NONE 0u
#define GS_GPS_FIX_FIX_2D 2u
#define GS_GPS_FIX_FIX_3D 3u
#define GS_GPS_FIX_DGPS 4u
#define GS_GPS_FIX_RTK 5u

#define GS_ID_IMU_RAW 0x01u
#define GS_PAYLOAD_IMU_RAW 18u
#define GS_SCALE_IMU_RAW_TEMPERATURE 0.01
#define GS_ID_ATTITUDE 0x02u
#define GS_PAYLOAD_ATTITUDE 15u
#define GS_SCALE_ATTITUDE_Q_W 6.103515625e-05
#define GS_SCALE_ATTITUDE_Q_X 6.103515625e-05
#define GS_SCALE_ATTITUDE_Q_Y 6.103515625e-05
#define GS_SCALE_ATTITUDE_Q_Z 6.103515625e-05
#define GS_SCALE_ATTITUDE_LAMBDA_GAIN 0.001
#define GS_ID_CONFIG 0x03u
#define GS_PAYLOAD_CONFIG 16u
#define GS_ID_STATUS 0x04u
#define GS_PAYLOAD_STATUS 13u
#define GS_SCALE_STATUS_BATTERY 0.001
#define GS_SCALE_STATUS_CPU_LOAD 0.5
#define GS_ID_MAG_RAW 0x05u
#define GS_PAYLOAD_MAG_RAW 10u
#define GS_SCALE_MAG_RAW_MAG_X 0.15
#define GS_SCALE_MAG_RAW_MAG_Y 0.15
#define GS_SCALE_MAG_RAW_MAG_Z 0.15
#define GS_ID_BARO 0x06u
#define GS_PAYLOAD_BARO 10u
#define GS_SCALE_BARO_PRESSURE 0.01
#define GS_SCALE_BARO_TEMPERATURE 0.01
#define GS_ID_GPS 0x07u
#define GS_PAYLOAD_GPS 26u
#define GS_SCALE_GPS_LAT 1e-07
#define GS_SCALE_GPS_LON 1e-07
#define GS_SCALE_GPS_ALT 0.001
#define GS_SCALE_GPS_VEL_N 0.01
#define GS_SCALE_GPS_VEL_E 0.01
#define GS_SCALE_GPS_VEL_D 0.01
#define GS_SCALE_GPS_HEADING 0.01
#define GS_ID_COMMAND 0x10u
#define GS_PAYLOAD_COMMAND 6u
#define GS_ID_ACK 0x11u
#define GS_PAYLOAD_ACK 3u

/* CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, no reflection, no final xor. */
static inline uint16_t gs_crc16(const uint8_t *data, size_t len)
{
    uint16_t crc = 0xFFFFu;
    for (size_t i = 0; i < len; i++) {
        crc ^= (uint16_t)((uint16_t)data[i] << 8);
        for (int bit = 0; bit < 8; bit++) {
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

/* Little-endian field access, independent of the CPU's byte order. */
static inline void gs_put_u16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void gs_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline uint16_t gs_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t gs_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint32_t gs_float_bits(float f) { uint32_t u; memcpy(&u, &f, sizeof u); return u; }
static inline float gs_bits_float(uint32_t u) { float f; memcpy(&f, &u, sizeof f); return f; }

/* Writes sync, length, type, seq and the CRC (big-endian) around a payload already at
 * out + GS_HEADER_BYTES. Returns the frame's length in bytes. */
static inline size_t gs_finish_frame(uint8_t *out, uint8_t type, uint8_t seq, uint8_t payload_len)
{
    out[0] = GS_SYNC;
    out[1] = payload_len;
    out[2] = type;
    out[3] = seq;
    uint16_t crc = gs_crc16(out + 1, (size_t)GS_HEADER_BYTES - 1u + payload_len);
    out[GS_HEADER_BYTES + payload_len] = (uint8_t)(crc >> 8);
    out[GS_HEADER_BYTES + payload_len + 1] = (uint8_t)crc;
    return (size_t)GS_HEADER_BYTES + payload_len + GS_CRC_BYTES;
}

/* IMU_RAW (0x01, down, frame fingerprint 0x631E0E3E): One MPU-6050 sample in sensor axes at the output rate. Counts convert to g and deg/s with the datasheet sensitivity of CONFIG's full scales (e.g. 16384 LSB/g at 2 g, 131 LSB/(deg/s) at 250 deg/s; groundstation/units.py). */
typedef struct {
    uint32_t t_us; /* us: device time of the sample; wraps every 71.6 min */
    int16_t acc_x; /* count: accelerometer x (specific force), sensor axes */
    int16_t acc_y; /* count: accelerometer y */
    int16_t acc_z; /* count: accelerometer z */
    int16_t gyr_x; /* count: gyroscope x (angular rate), sensor axes */
    int16_t gyr_y; /* count: gyroscope y */
    int16_t gyr_z; /* count: gyroscope z */
    int16_t temperature; /* degC x 0.01: die temperature (firmware converts the MPU-6050's raw/340 + 36.53) */
} gs_imu_raw_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_imu_raw(uint8_t *out, uint8_t seq, const gs_imu_raw_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    gs_put_u32(p + 0, (uint32_t)m->t_us);
    gs_put_u16(p + 4, (uint16_t)m->acc_x);
    gs_put_u16(p + 6, (uint16_t)m->acc_y);
    gs_put_u16(p + 8, (uint16_t)m->acc_z);
    gs_put_u16(p + 10, (uint16_t)m->gyr_x);
    gs_put_u16(p + 12, (uint16_t)m->gyr_y);
    gs_put_u16(p + 14, (uint16_t)m->gyr_z);
    gs_put_u16(p + 16, (uint16_t)m->temperature);
    return gs_finish_frame(out, GS_ID_IMU_RAW, seq, GS_PAYLOAD_IMU_RAW);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_imu_raw(const uint8_t *p, gs_imu_raw_t *m)
{
    m->t_us = (uint32_t)gs_get_u32(p + 0);
    m->acc_x = (int16_t)gs_get_u16(p + 4);
    m->acc_y = (int16_t)gs_get_u16(p + 6);
    m->acc_z = (int16_t)gs_get_u16(p + 8);
    m->gyr_x = (int16_t)gs_get_u16(p + 10);
    m->gyr_y = (int16_t)gs_get_u16(p + 12);
    m->gyr_z = (int16_t)gs_get_u16(p + 14);
    m->temperature = (int16_t)gs_get_u16(p + 16);
}

/* ATTITUDE (0x02, down, frame fingerprint 0x78E86498): The onboard AHF estimate: quaternion (w first) rotating body (forward-right-down) vectors into north-east-down, see docs/conventions.md. */
typedef struct {
    uint32_t t_us; /* us: device time of the IMU sample the estimate includes */
    int16_t q_w; /* 1 x 6.103515625e-05: quaternion w, Q2.14 fixed point */
    int16_t q_x; /* 1 x 6.103515625e-05: quaternion x, Q2.14 fixed point */
    int16_t q_y; /* 1 x 6.103515625e-05: quaternion y, Q2.14 fixed point */
    int16_t q_z; /* 1 x 6.103515625e-05: quaternion z, Q2.14 fixed point */
    uint16_t lambda_gain; /* 1 x 0.001: the onboard filter's current lambda (seed 000 eq. 20) */
    uint8_t flags; /* bits: bit 0 initialising, bit 1 gyro over range, bit 2 accelerometer rejected */
} gs_attitude_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_attitude(uint8_t *out, uint8_t seq, const gs_attitude_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    gs_put_u32(p + 0, (uint32_t)m->t_us);
    gs_put_u16(p + 4, (uint16_t)m->q_w);
    gs_put_u16(p + 6, (uint16_t)m->q_x);
    gs_put_u16(p + 8, (uint16_t)m->q_y);
    gs_put_u16(p + 10, (uint16_t)m->q_z);
    gs_put_u16(p + 12, (uint16_t)m->lambda_gain);
    p[14] = (uint8_t)m->flags;
    return gs_finish_frame(out, GS_ID_ATTITUDE, seq, GS_PAYLOAD_ATTITUDE);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_attitude(const uint8_t *p, gs_attitude_t *m)
{
    m->t_us = (uint32_t)gs_get_u32(p + 0);
    m->q_w = (int16_t)gs_get_u16(p + 4);
    m->q_x = (int16_t)gs_get_u16(p + 6);
    m->q_y = (int16_t)gs_get_u16(p + 8);
    m->q_z = (int16_t)gs_get_u16(p + 10);
    m->lambda_gain = (uint16_t)gs_get_u16(p + 12);
    m->flags = (uint8_t)p[14];
}

/* CONFIG (0x03, down, frame fingerprint 0x5FD4506C): The aircraft's configuration, sent at start and on request. protocol_version and schema_fingerprint stay the first two fields in every version. */
typedef struct {
    uint8_t protocol_version; /* 1: framing version (framing.protocol_version) */
    uint32_t schema_fingerprint; /* 1: CRC-32 of the spec the firmware was built from; the ground station looks up its frame types in firmware_protocol/known_specs.toml and reports those that differ */
    uint8_t fw_major; /* 1: firmware version, major */
    uint8_t fw_minor; /* 1: firmware version, minor */
    uint8_t fw_patch; /* 1: firmware version, patch */
    uint8_t accel_fs_g; /* g: accelerometer full scale: 2, 4, 8 or 16 */
    uint16_t gyro_fs_dps; /* deg/s: gyroscope full scale: 250, 500, 1000 or 2000 */
    uint16_t rate_hz; /* Hz: output rate of IMU_RAW / ATTITUDE */
    uint8_t mode; /* enum: what is sent */
    uint8_t mounting; /* index: sensor mounting, one of the 24 axis-aligned rotations (docs/conventions.md) */
    uint8_t gyro_calibration; /* enum: none: no calibration, the gyro's turn-on bias; boot: measured at this boot, the craft still; stored: the craft moved during the boot calibration, so the last calibration (kept over resets) is used; command: measured on calibrate_gyro */
} gs_config_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_config(uint8_t *out, uint8_t seq, const gs_config_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    p[0] = (uint8_t)m->protocol_version;
    gs_put_u32(p + 1, (uint32_t)m->schema_fingerprint);
    p[5] = (uint8_t)m->fw_major;
    p[6] = (uint8_t)m->fw_minor;
    p[7] = (uint8_t)m->fw_patch;
    p[8] = (uint8_t)m->accel_fs_g;
    gs_put_u16(p + 9, (uint16_t)m->gyro_fs_dps);
    gs_put_u16(p + 11, (uint16_t)m->rate_hz);
    p[13] = (uint8_t)m->mode;
    p[14] = (uint8_t)m->mounting;
    p[15] = (uint8_t)m->gyro_calibration;
    return gs_finish_frame(out, GS_ID_CONFIG, seq, GS_PAYLOAD_CONFIG);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_config(const uint8_t *p, gs_config_t *m)
{
    m->protocol_version = (uint8_t)p[0];
    m->schema_fingerprint = (uint32_t)gs_get_u32(p + 1);
    m->fw_major = (uint8_t)p[5];
    m->fw_minor = (uint8_t)p[6];
    m->fw_patch = (uint8_t)p[7];
    m->accel_fs_g = (uint8_t)p[8];
    m->gyro_fs_dps = (uint16_t)gs_get_u16(p + 9);
    m->rate_hz = (uint16_t)gs_get_u16(p + 11);
    m->mode = (uint8_t)p[13];
    m->mounting = (uint8_t)p[14];
    m->gyro_calibration = (uint8_t)p[15];
}

/* STATUS (0x04, down, frame fingerprint 0x24539ACE): Heartbeat at 1 Hz: power, the aircraft radio's view of the link, load. */
typedef struct {
    uint32_t t_us; /* us: device time */
    uint16_t battery; /* V x 0.001: battery voltage */
    uint16_t retransmits; /* 1: radio auto-retransmissions in the last second */
    uint16_t lost_acks; /* 1: payloads the radio gave up on (no acknowledgement) in the last second */
    uint8_t cpu_load; /* % x 0.5: CPU load */
    uint16_t flags; /* bits: bit 0 gyro calibration running, bit 1 low battery, bit 2 IMU error, bit 3 radio TX FIFO overflow */
} gs_status_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_status(uint8_t *out, uint8_t seq, const gs_status_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    gs_put_u32(p + 0, (uint32_t)m->t_us);
    gs_put_u16(p + 4, (uint16_t)m->battery);
    gs_put_u16(p + 6, (uint16_t)m->retransmits);
    gs_put_u16(p + 8, (uint16_t)m->lost_acks);
    p[10] = (uint8_t)m->cpu_load;
    gs_put_u16(p + 11, (uint16_t)m->flags);
    return gs_finish_frame(out, GS_ID_STATUS, seq, GS_PAYLOAD_STATUS);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_status(const uint8_t *p, gs_status_t *m)
{
    m->t_us = (uint32_t)gs_get_u32(p + 0);
    m->battery = (uint16_t)gs_get_u16(p + 4);
    m->retransmits = (uint16_t)gs_get_u16(p + 6);
    m->lost_acks = (uint16_t)gs_get_u16(p + 8);
    m->cpu_load = (uint8_t)p[10];
    m->flags = (uint16_t)gs_get_u16(p + 11);
}

/* MAG_RAW (0x05, down, frame fingerprint 0x70619AF2): Magnetometer sample in sensor axes. */
typedef struct {
    uint32_t t_us; /* us: device time */
    int16_t mag_x; /* uT x 0.15: magnetic field x */
    int16_t mag_y; /* uT x 0.15: magnetic field y */
    int16_t mag_z; /* uT x 0.15: magnetic field z */
} gs_mag_raw_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_mag_raw(uint8_t *out, uint8_t seq, const gs_mag_raw_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    gs_put_u32(p + 0, (uint32_t)m->t_us);
    gs_put_u16(p + 4, (uint16_t)m->mag_x);
    gs_put_u16(p + 6, (uint16_t)m->mag_y);
    gs_put_u16(p + 8, (uint16_t)m->mag_z);
    return gs_finish_frame(out, GS_ID_MAG_RAW, seq, GS_PAYLOAD_MAG_RAW);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_mag_raw(const uint8_t *p, gs_mag_raw_t *m)
{
    m->t_us = (uint32_t)gs_get_u32(p + 0);
    m->mag_x = (int16_t)gs_get_u16(p + 4);
    m->mag_y = (int16_t)gs_get_u16(p + 6);
    m->mag_z = (int16_t)gs_get_u16(p + 8);
}

/* BARO (0x06, down, frame fingerprint 0x94CBB3F4): Barometer sample. */
typedef struct {
    uint32_t t_us; /* us: device time */
    uint32_t pressure; /* Pa x 0.01: static pressure */
    int16_t temperature; /* degC x 0.01: sensor temperature */
} gs_baro_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_baro(uint8_t *out, uint8_t seq, const gs_baro_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    gs_put_u32(p + 0, (uint32_t)m->t_us);
    gs_put_u32(p + 4, (uint32_t)m->pressure);
    gs_put_u16(p + 8, (uint16_t)m->temperature);
    return gs_finish_frame(out, GS_ID_BARO, seq, GS_PAYLOAD_BARO);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_baro(const uint8_t *p, gs_baro_t *m)
{
    m->t_us = (uint32_t)gs_get_u32(p + 0);
    m->pressure = (uint32_t)gs_get_u32(p + 4);
    m->temperature = (int16_t)gs_get_u16(p + 8);
}

/* GPS (0x07, down, frame fingerprint 0xD7E10AB7): GNSS solution. */
typedef struct {
    uint32_t t_us; /* us: device time of the solution */
    int32_t lat; /* deg x 1e-07: latitude */
    int32_t lon; /* deg x 1e-07: longitude */
    int32_t alt; /* m x 0.001: altitude above mean sea level */
    int16_t vel_n; /* m/s x 0.01: velocity north */
    int16_t vel_e; /* m/s x 0.01: velocity east */
    int16_t vel_d; /* m/s x 0.01: velocity down */
    uint16_t heading; /* deg x 0.01: heading (dual-antenna or course over ground), 0..360; 0xFFFF: no heading */
    uint8_t fix_type; /* enum: fix type */
    uint8_t satellites; /* 1: satellites used */
} gs_gps_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_gps(uint8_t *out, uint8_t seq, const gs_gps_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    gs_put_u32(p + 0, (uint32_t)m->t_us);
    gs_put_u32(p + 4, (uint32_t)m->lat);
    gs_put_u32(p + 8, (uint32_t)m->lon);
    gs_put_u32(p + 12, (uint32_t)m->alt);
    gs_put_u16(p + 16, (uint16_t)m->vel_n);
    gs_put_u16(p + 18, (uint16_t)m->vel_e);
    gs_put_u16(p + 20, (uint16_t)m->vel_d);
    gs_put_u16(p + 22, (uint16_t)m->heading);
    p[24] = (uint8_t)m->fix_type;
    p[25] = (uint8_t)m->satellites;
    return gs_finish_frame(out, GS_ID_GPS, seq, GS_PAYLOAD_GPS);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_gps(const uint8_t *p, gs_gps_t *m)
{
    m->t_us = (uint32_t)gs_get_u32(p + 0);
    m->lat = (int32_t)gs_get_u32(p + 4);
    m->lon = (int32_t)gs_get_u32(p + 8);
    m->alt = (int32_t)gs_get_u32(p + 12);
    m->vel_n = (int16_t)gs_get_u16(p + 16);
    m->vel_e = (int16_t)gs_get_u16(p + 18);
    m->vel_d = (int16_t)gs_get_u16(p + 20);
    m->heading = (uint16_t)gs_get_u16(p + 22);
    m->fix_type = (uint8_t)p[24];
    m->satellites = (uint8_t)p[25];
}

/* COMMAND (0x10, up, frame fingerprint 0xB7C2EF0C): Ground to aircraft. The frame's seq identifies the command; the aircraft answers with ACK. */
typedef struct {
    uint8_t command; /* enum: what to do */
    uint8_t param; /* 1: set_mode: the mode; set_filter_param: the filter_param; otherwise 0 */
    float value; /* 1: set_filter_param: the new value; calibrate_gyro: averaging time in s; otherwise 0 */
} gs_command_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_command(uint8_t *out, uint8_t seq, const gs_command_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    p[0] = (uint8_t)m->command;
    p[1] = (uint8_t)m->param;
    gs_put_u32(p + 2, gs_float_bits(m->value));
    return gs_finish_frame(out, GS_ID_COMMAND, seq, GS_PAYLOAD_COMMAND);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_command(const uint8_t *p, gs_command_t *m)
{
    m->command = (uint8_t)p[0];
    m->param = (uint8_t)p[1];
    m->value = gs_bits_float(gs_get_u32(p + 2));
}

/* ACK (0x11, down, frame fingerprint 0x21082842): The aircraft's answer to a COMMAND. */
typedef struct {
    uint8_t command_seq; /* 1: seq of the COMMAND frame answered */
    uint8_t command; /* enum: the command answered */
    uint8_t result; /* enum: outcome */
} gs_ack_t;

/* Packs m into out (room for GS_MAX_FRAME_BYTES); returns the frame's length. */
static inline size_t gs_pack_ack(uint8_t *out, uint8_t seq, const gs_ack_t *m)
{
    uint8_t *p = out + GS_HEADER_BYTES;
    p[0] = (uint8_t)m->command_seq;
    p[1] = (uint8_t)m->command;
    p[2] = (uint8_t)m->result;
    return gs_finish_frame(out, GS_ID_ACK, seq, GS_PAYLOAD_ACK);
}

/* Reads the payload (out + GS_HEADER_BYTES of a checked frame) into m. */
static inline void gs_unpack_ack(const uint8_t *p, gs_ack_t *m)
{
    m->command_seq = (uint8_t)p[0];
    m->command = (uint8_t)p[1];
    m->result = (uint8_t)p[2];
}

/* The payload length of a known frame type, or -1 for a type this spec lacks. */
static inline int gs_payload_size(uint8_t type)
{
    switch (type) {
    case GS_ID_IMU_RAW: return (int)GS_PAYLOAD_IMU_RAW;
    case GS_ID_ATTITUDE: return (int)GS_PAYLOAD_ATTITUDE;
    case GS_ID_CONFIG: return (int)GS_PAYLOAD_CONFIG;
    case GS_ID_STATUS: return (int)GS_PAYLOAD_STATUS;
    case GS_ID_MAG_RAW: return (int)GS_PAYLOAD_MAG_RAW;
    case GS_ID_BARO: return (int)GS_PAYLOAD_BARO;
    case GS_ID_GPS: return (int)GS_PAYLOAD_GPS;
    case GS_ID_COMMAND: return (int)GS_PAYLOAD_COMMAND;
    case GS_ID_ACK: return (int)GS_PAYLOAD_ACK;
    default: return -1;
    }
}

/* Checks a complete frame of len bytes: sync, length, known type, CRC. Returns its payload
 * length, or -1 when it is not an intact frame of a known type. */
static inline int gs_check_frame(const uint8_t *frame, size_t len)
{
    if (len < GS_HEADER_BYTES + GS_CRC_BYTES || frame[0] != GS_SYNC) return -1;
    int size = gs_payload_size(frame[2]);
    if (size < 0 || frame[1] != (uint8_t)size || len != (size_t)size + GS_HEADER_BYTES + GS_CRC_BYTES) return -1;
    uint16_t crc = gs_crc16(frame + 1, (size_t)GS_HEADER_BYTES - 1u + (size_t)size);
    if (frame[len - 2] != (uint8_t)(crc >> 8) || frame[len - 1] != (uint8_t)crc) return -1;
    return size;
}

#endif /* GS_PROTOCOL_H */
