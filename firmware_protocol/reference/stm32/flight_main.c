/* The flight board: MPU-6050 -> firmware core (onboard AHF, frames) -> nRF24L01+, 100 Hz.
 *
 * Each period: read the MPU-6050 (timestamped), hand the sample to gs_flight_sample(), send each
 * frame as one radio payload, pass uplink payloads that came back on acknowledgements to
 * gs_flight_uplink(), and write a finished gyro calibration into the chip's offset registers. The
 * calibration is kept in the backup registers too: after a reset in flight the core uses it when the
 * craft moves during the boot calibration (they survive a reset, not a power cut: VBAT is VDD here).
 *
 * LED (PC13): fast blink (5 Hz) while the gyro calibrates (keep the craft still); one short flash a
 * second while streaming; steady on: no MPU-6050 or no radio (nothing is sent). */
#include <math.h>

#include "board.h"
#include "gs_flight.h"
#include "mpu6050.h"
#include "nrf24.h"

/* The configuration this board streams (CONFIG carries it to the ground station). */
#define RATE_HZ 100u
#define ACCEL_FS_G 4u
#define GYRO_FS_DPS 500u
#define MOUNTING 1u /* the breakout flat, components up, x arrow to the nose (docs/conventions.md) */
#define FIRMWARE_VERSION {1u, 0u, 0u}
/* Battery on PA0 through a divider 10 k (to the battery) / 3.3 k (to ground): 12.6 V reads 3.13 V. */
#define BATTERY_DIVIDER ((10.0 + 3.3) / 3.3)
#define ADC_VOLTS_PER_COUNT (3.3 / 4095.0)

static void battery_init(void)
{
    RCC_APB2ENR |= RCC_APB2ENR_ADC1EN;
    gpio_mode(GPIOA_BASE, 0, GPIO_ANALOG);
    ADC1_SMPR2 = 7u;            /* channel 0: 239.5 cycles, for the divider's impedance */
    ADC1_SQR3 = 0u;             /* one conversion: channel 0 */
    ADC1_CR2 = ADC_CR2_ADON;
    delay_us(10);
    ADC1_CR2 |= ADC_CR2_CAL;
    while (ADC1_CR2 & ADC_CR2_CAL) {}
    ADC1_CR2 |= ADC_CR2_EXTSEL_SWSTART | ADC_CR2_EXTTRIG;
}

static double battery_v(void)
{
    ADC1_CR2 |= ADC_CR2_SWSTART;
    while (!(ADC1_SR & ADC_SR_EOC)) {}
    return (double)(ADC1_DR & 0xFFFu) * ADC_VOLTS_PER_COUNT * BATTERY_DIVIDER;
}

/* The gyro offset in the backup registers: a marker in DR1, then each axis in 1e-4 deg/s as two halves. */
#define STORED_MARKER 0x6C01u
#define STORED_LSB_PER_DPS 1e4

static void backup_init(void)
{
    RCC_APB1ENR |= RCC_APB1ENR_PWREN | RCC_APB1ENR_BKPEN;
    PWR_CR |= PWR_CR_DBP;
}

static int stored_gyro_offset(double offset_dps[3])
{
    if ((BKP_DR(1) & 0xFFFFu) != STORED_MARKER) return 0;
    for (unsigned i = 0; i < 3; i++) {
        uint32_t bits = (BKP_DR(2 + 2 * i) & 0xFFFFu) << 16 | (BKP_DR(3 + 2 * i) & 0xFFFFu);
        offset_dps[i] = (double)(int32_t)bits / STORED_LSB_PER_DPS;
    }
    return 1;
}

static void store_gyro_offset(const double offset_dps[3])
{
    for (unsigned i = 0; i < 3; i++) {
        uint32_t bits = (uint32_t)(int32_t)lrint(offset_dps[i] * STORED_LSB_PER_DPS);
        BKP_DR(2 + 2 * i) = bits >> 16;
        BKP_DR(3 + 2 * i) = bits & 0xFFFFu;
    }
    BKP_DR(1) = STORED_MARKER;
}

static void fault(void)
{
    led(1);
    for (;;) {}
}

int main(void)
{
    board_init();
    battery_init();
    if (mpu6050_init(ACCEL_FS_G, GYRO_FS_DPS, RATE_HZ) != 0 || nrf24_init(0) != 0) fault();

    static gs_flight flight;
    gs_flight_config config = {
        .rate_hz = RATE_HZ, .accel_fs_g = ACCEL_FS_G, .gyro_fs_dps = GYRO_FS_DPS, .mounting = MOUNTING,
        .mode = GS_MODE_BOTH, .boot_calibration_s = 1.0, .fw_version = FIRMWARE_VERSION,
    };
    gs_ahf_default_settings(&config.ahf);
    if (gs_flight_init(&flight, &config) != 0) fault();
    backup_init();
    double chip_offset_dps[3] = {0.0, 0.0, 0.0}; /* what the offset registers hold: 0 after mpu6050_init */
    double stored_dps[3];
    if (stored_gyro_offset(stored_dps)) gs_flight_restore_gyro_offset(&flight, stored_dps);

    static uint8_t out[GS_FLIGHT_MAX_OUT];
    uint8_t uplink[NRF24_MAX_PAYLOAD];
    gs_sample sample = {0};
    uint32_t period_us = 1000000u / RATE_HZ, next = micros(), busy_us = 0, second_start = next;
    uint16_t retransmits = 0, lost = 0;
    for (uint32_t k = 0;; k++) {
        next += period_us;
        while ((int32_t)(micros() - next) < 0) {}
        uint32_t t0 = micros();
        sample.t_us = t0;
        sample.port_flags = mpu6050_read(sample.acc, &sample.temperature, sample.gyr) ? GS_STATUS_IMU_ERROR : 0u;
        sample.battery_v = battery_v();
        size_t n = gs_flight_sample(&flight, &sample, out, sizeof out);
        int status_sent = 0;
        for (size_t i = 0; i < n; i += gs_frame_length(out + i)) {
            nrf24_result r = nrf24_send(out + i, gs_frame_length(out + i), uplink);
            retransmits = (uint16_t)(retransmits + r.retransmits);
            lost = (uint16_t)(lost + !r.acknowledged);
            if (r.ack_len) gs_flight_uplink(&flight, uplink, r.ack_len);
            status_sent |= out[i + 2] == GS_ID_STATUS;
        }
        double offset_dps[3];
        if (gs_flight_take_gyro_offset(&flight, offset_dps)) {
            if (mpu6050_subtract_gyro_offset(offset_dps) != 0) sample.port_flags |= GS_STATUS_IMU_ERROR;
            for (unsigned i = 0; i < 3; i++) chip_offset_dps[i] += offset_dps[i];
            store_gyro_offset(chip_offset_dps);
        }
        busy_us += micros() - t0;
        if ((int32_t)(micros() - next) > (int32_t)period_us) next = micros(); /* overrun: no burst to catch up */
        if (status_sent) { /* STATUS reports the second before it */
            sample.retransmits = retransmits;
            sample.lost_acks = lost;
            retransmits = lost = 0;
            uint32_t elapsed = micros() - second_start;
            sample.cpu_load_pct = elapsed ? 100.0 * busy_us / elapsed : 0.0;
            busy_us = 0;
            second_start = micros();
        }
        if (flight.calibration_n) {
            led(k % (RATE_HZ / 5u) < RATE_HZ / 10u);
        } else {
            led(k % RATE_HZ < RATE_HZ / 20u);
        }
    }
}
