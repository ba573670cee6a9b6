/* See mpu6050.h. Registers: MPU-6000/6050 Register Map rev 4.2; offset registers: InvenSense's
 * "MPU Hardware Offset Registers" application note. I2C: RM0008 26.3.3 (master, polled). */
#include "mpu6050.h"

#include <math.h>

#include "board.h"

#define ADDRESS 0x68u
#define REG_XG_OFFS_USRH 0x13u
#define REG_SMPLRT_DIV 0x19u
#define REG_CONFIG 0x1Au
#define REG_GYRO_CONFIG 0x1Bu
#define REG_ACCEL_CONFIG 0x1Cu
#define REG_ACCEL_XOUT_H 0x3Bu
#define REG_PWR_MGMT_1 0x6Bu
#define REG_WHO_AM_I 0x75u
#define GYRO_OFFSET_LSB_PER_DPS 32.8
#define TIMEOUT_US 2000u

static int wait_sr1(uint32_t bits)
{
    uint32_t start = micros();
    while (!(I2C1_SR1 & bits)) {
        if ((I2C1_SR1 & I2C_SR1_AF) || micros() - start > TIMEOUT_US) {
            I2C1_SR1 = 0;
            I2C1_CR1 |= I2C_CR1_STOP;
            return -1;
        }
    }
    return 0;
}

/* START and the address byte; read: 1 for a read transfer. ADDR is left set. */
static int start(int read)
{
    I2C1_CR1 |= I2C_CR1_START;
    if (wait_sr1(I2C_SR1_SB)) return -1;
    I2C1_DR = (ADDRESS << 1) | (read ? 1u : 0u);
    return wait_sr1(I2C_SR1_ADDR);
}

static int write_regs(uint8_t reg, const uint8_t *data, unsigned len)
{
    if (start(0)) return -1;
    (void)I2C1_SR2; /* clears ADDR */
    I2C1_DR = reg;
    for (unsigned i = 0; i < len; i++) {
        if (wait_sr1(I2C_SR1_TXE)) return -1;
        I2C1_DR = data[i];
    }
    if (wait_sr1(I2C_SR1_BTF)) return -1;
    I2C1_CR1 |= I2C_CR1_STOP;
    return 0;
}

static int write_reg(uint8_t reg, uint8_t value) { return write_regs(reg, &value, 1); }

static int read_regs(uint8_t reg, uint8_t *out, unsigned len)
{
    if (start(0)) return -1;
    (void)I2C1_SR2;
    I2C1_DR = reg;
    if (wait_sr1(I2C_SR1_BTF)) return -1;
    if (len > 1u) I2C1_CR1 |= I2C_CR1_ACK;
    if (start(1)) return -1;
    if (len == 1u) I2C1_CR1 &= ~I2C_CR1_ACK; /* NACK the only byte */
    (void)I2C1_SR2;
    for (unsigned i = 0; i < len; i++) {
        if (i + 1u == len) { /* NACK and STOP after the last byte */
            I2C1_CR1 &= ~I2C_CR1_ACK;
            I2C1_CR1 |= I2C_CR1_STOP;
        }
        if (wait_sr1(I2C_SR1_RXNE)) return -1;
        out[i] = (uint8_t)I2C1_DR;
    }
    return 0;
}

int mpu6050_init(unsigned accel_fs_g, unsigned gyro_fs_dps, unsigned rate_hz)
{
    RCC_APB1ENR |= RCC_APB1ENR_I2C1EN;
    gpio_mode(GPIOB_BASE, 6, GPIO_AF_OPEN_DRAIN_50MHZ);
    gpio_mode(GPIOB_BASE, 7, GPIO_AF_OPEN_DRAIN_50MHZ);
    I2C1_CR1 = I2C_CR1_SWRST;
    I2C1_CR1 = 0;
    I2C1_CR2 = 36u;              /* APB1 MHz */
    I2C1_CCR = (1u << 15) | 30u; /* fast mode: 36 MHz / (3 x 30) = 400 kHz */
    I2C1_TRISE = 12u;            /* 300 ns / 27.8 ns + 1 */
    I2C1_CR1 = I2C_CR1_PE;

    unsigned afs = accel_fs_g == 2u ? 0u : accel_fs_g == 4u ? 1u : accel_fs_g == 8u ? 2u : 3u;
    unsigned fs = gyro_fs_dps == 250u ? 0u : gyro_fs_dps == 500u ? 1u : gyro_fs_dps == 1000u ? 2u : 3u;
    uint8_t who = 0;
    if (write_reg(REG_PWR_MGMT_1, 0x80u)) return -1; /* reset */
    delay_us(100000);
    if (read_regs(REG_WHO_AM_I, &who, 1) || who != 0x68u) return -1;
    if (write_reg(REG_PWR_MGMT_1, 0x01u)          /* awake, clocked by the X gyro's PLL */
        || write_reg(REG_CONFIG, 0x03u)            /* DLPF 44 Hz: the gyro samples at 1 kHz */
        || write_reg(REG_SMPLRT_DIV, (uint8_t)(1000u / rate_hz - 1u))
        || write_reg(REG_GYRO_CONFIG, (uint8_t)(fs << 3))
        || write_reg(REG_ACCEL_CONFIG, (uint8_t)(afs << 3))) {
        return -1;
    }
    delay_us(50000); /* the gyro's start-up time */
    return 0;
}

static int16_t big_endian(const uint8_t *p) { return (int16_t)((uint16_t)(p[0] << 8) | p[1]); }

int mpu6050_read(int16_t acc[3], int16_t *temperature, int16_t gyr[3])
{
    uint8_t raw[14];
    if (read_regs(REG_ACCEL_XOUT_H, raw, sizeof raw)) return -1;
    for (int i = 0; i < 3; i++) {
        acc[i] = big_endian(raw + 2 * i);
        gyr[i] = big_endian(raw + 8 + 2 * i);
    }
    *temperature = big_endian(raw + 6);
    return 0;
}

int mpu6050_subtract_gyro_offset(const double offset_dps[3])
{
    uint8_t raw[6];
    if (read_regs(REG_XG_OFFS_USRH, raw, sizeof raw)) return -1;
    for (int i = 0; i < 3; i++) {
        long value = big_endian(raw + 2 * i) - lrint(offset_dps[i] * GYRO_OFFSET_LSB_PER_DPS);
        value = value < -32768 ? -32768 : value > 32767 ? 32767 : value;
        raw[2 * i] = (uint8_t)((uint16_t)value >> 8);
        raw[2 * i + 1] = (uint8_t)value;
    }
    return write_regs(REG_XG_OFFS_USRH, raw, sizeof raw);
}
