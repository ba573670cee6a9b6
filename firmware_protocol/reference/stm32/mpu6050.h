/* MPU-6050 on I2C1 at 400 kHz (SCL PB6, SDA PB7; AD0 low: address 0x68). */
#ifndef MPU6050_H
#define MPU6050_H

#include <stdint.h>

/* Wakes the chip on its gyro PLL with the full scales (2/4/8/16 g, 250/500/1000/2000 deg/s), the
 * digital low-pass at 44 Hz and the sample rate rate_hz (1 kHz divided). Returns 0, or -1 when no
 * MPU-6050 answers (WHO_AM_I). */
int mpu6050_init(unsigned accel_fs_g, unsigned gyro_fs_dps, unsigned rate_hz);

/* ACCEL_X..Z, TEMP, GYRO_X..Z counts in one burst (consistent); returns 0, or -1 on a bus error. */
int mpu6050_read(int16_t acc[3], int16_t *temperature, int16_t gyr[3]);

/* Subtracts offset_dps from what the gyro reports, in its offset registers (XG_OFFS_USR...: 32.8 LSB
 * per deg/s whatever the full scale, added to the output). Returns 0, or -1 on a bus error. */
int mpu6050_subtract_gyro_offset(const double offset_dps[3]);

#endif /* MPU6050_H */
