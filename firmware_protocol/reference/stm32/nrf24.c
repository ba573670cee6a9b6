/* See nrf24.h. Register map and commands: nRF24L01+ Product Specification v1.0, sections 8 and 9. */
#include "nrf24.h"

#include "board.h"

#define CMD_R_REGISTER 0x00u
#define CMD_W_REGISTER 0x20u
#define CMD_R_RX_PAYLOAD 0x61u
#define CMD_W_TX_PAYLOAD 0xA0u
#define CMD_FLUSH_TX 0xE1u
#define CMD_FLUSH_RX 0xE2u
#define CMD_R_RX_PL_WID 0x60u
#define CMD_W_ACK_PAYLOAD_P0 0xA8u
#define CMD_NOP 0xFFu

#define REG_CONFIG 0x00u
#define REG_EN_AA 0x01u
#define REG_EN_RXADDR 0x02u
#define REG_SETUP_AW 0x03u
#define REG_SETUP_RETR 0x04u
#define REG_RF_CH 0x05u
#define REG_RF_SETUP 0x06u
#define REG_STATUS 0x07u
#define REG_OBSERVE_TX 0x08u
#define REG_RX_ADDR_P0 0x0Au
#define REG_TX_ADDR 0x10u
#define REG_FIFO_STATUS 0x17u
#define REG_DYNPD 0x1Cu
#define REG_FEATURE 0x1Du

#define STATUS_RX_DR (1u << 6)
#define STATUS_TX_DS (1u << 5)
#define STATUS_MAX_RT (1u << 4)
#define FIFO_RX_EMPTY (1u << 0)
#define FIFO_TX_FULL (1u << 5)

#define CONFIG_PRIM_RX (1u << 0)
#define CONFIG_PWR_UP (1u << 1)
#define CONFIG_CRC_2_BYTES ((1u << 3) | (1u << 2))

#define CHANNEL 76u
static const uint8_t address[5] = {'G', 'S', 'L', 'N', 'K'};

static void csn(int high)
{
    if (high) {
        GPIO_BSRR(GPIOA_BASE) = 1u << 4;
    } else {
        GPIO_BRR(GPIOA_BASE) = 1u << 4;
    }
}

static void ce(int high)
{
    if (high) {
        GPIO_BSRR(GPIOB_BASE) = 1u << 0;
    } else {
        GPIO_BRR(GPIOB_BASE) = 1u << 0;
    }
}

/* One command with len bytes out of tx (NULL: zeros) and into rx (NULL: ignored); returns STATUS. */
static uint8_t command(uint8_t cmd, const uint8_t *tx, uint8_t *rx, size_t len)
{
    csn(0);
    uint8_t status = spi1_transfer(cmd);
    for (size_t i = 0; i < len; i++) {
        uint8_t in = spi1_transfer(tx ? tx[i] : 0u);
        if (rx) rx[i] = in;
    }
    csn(1);
    return status;
}

static void write_reg(uint8_t reg, uint8_t value) { command((uint8_t)(CMD_W_REGISTER | reg), &value, NULL, 1); }

static uint8_t read_reg(uint8_t reg)
{
    uint8_t value;
    command((uint8_t)(CMD_R_REGISTER | reg), NULL, &value, 1);
    return value;
}

int nrf24_init(int receiver)
{
    spi1_init();
    gpio_mode(GPIOA_BASE, 4, GPIO_OUTPUT_50MHZ);
    gpio_mode(GPIOB_BASE, 0, GPIO_OUTPUT_50MHZ);
    csn(1);
    ce(0);
    delay_us(100000); /* power-on reset */
    write_reg(REG_CONFIG, CONFIG_CRC_2_BYTES);
    write_reg(REG_SETUP_AW, 3u);     /* 5-byte addresses */
    write_reg(REG_RF_CH, CHANNEL);
    write_reg(REG_RF_SETUP, 0x06u);  /* 1 Mbps, 0 dBm */
    /* 500 us between tries (payloads on acknowledgements need it), 2 retransmissions: a frame the
     * bridge never hears costs 3 tries of about 1 ms, so a sample's frames still fit its 10 ms */
    write_reg(REG_SETUP_RETR, 0x12u);
    write_reg(REG_EN_AA, 1u);
    write_reg(REG_EN_RXADDR, 1u);
    write_reg(REG_FEATURE, 0x06u);   /* dynamic payload length, payloads on acknowledgements */
    write_reg(REG_DYNPD, 1u);
    command((uint8_t)(CMD_W_REGISTER | REG_TX_ADDR), address, NULL, sizeof address);
    command((uint8_t)(CMD_W_REGISTER | REG_RX_ADDR_P0), address, NULL, sizeof address);
    if (read_reg(REG_RF_CH) != CHANNEL || read_reg(REG_FEATURE) != 0x06u) return -1;
    command(CMD_FLUSH_TX, NULL, NULL, 0);
    command(CMD_FLUSH_RX, NULL, NULL, 0);
    write_reg(REG_STATUS, STATUS_RX_DR | STATUS_TX_DS | STATUS_MAX_RT);
    write_reg(REG_CONFIG, (uint8_t)(CONFIG_CRC_2_BYTES | CONFIG_PWR_UP | (receiver ? CONFIG_PRIM_RX : 0u)));
    delay_us(2000); /* power-up to standby */
    if (receiver) ce(1);
    return 0;
}

/* The next payload in the RX FIFO into out; 0 when empty (or a corrupt width, flushed). */
static size_t read_payload(uint8_t *out)
{
    if (read_reg(REG_FIFO_STATUS) & FIFO_RX_EMPTY) return 0;
    uint8_t width;
    command(CMD_R_RX_PL_WID, NULL, &width, 1);
    if (width == 0 || width > NRF24_MAX_PAYLOAD) {
        command(CMD_FLUSH_RX, NULL, NULL, 0);
        return 0;
    }
    command(CMD_R_RX_PAYLOAD, NULL, out, width);
    return width;
}

nrf24_result nrf24_send(const uint8_t *payload, size_t len, uint8_t *ack_payload)
{
    nrf24_result result = {0, 0, 0};
    command(CMD_W_TX_PAYLOAD, payload, NULL, len);
    ce(1);
    delay_us(15); /* a CE pulse of at least 10 us starts the transmission */
    ce(0);
    uint32_t start = micros();
    uint8_t status;
    do {
        status = command(CMD_NOP, NULL, NULL, 0);
    } while (!(status & (STATUS_TX_DS | STATUS_MAX_RT)) && micros() - start < 3000u);
    result.retransmits = read_reg(REG_OBSERVE_TX) & 0x0Fu;
    if (status & STATUS_TX_DS) {
        result.acknowledged = 1;
        if (status & STATUS_RX_DR) result.ack_len = read_payload(ack_payload);
    } else {
        command(CMD_FLUSH_TX, NULL, NULL, 0); /* given up (or no radio): drop it */
    }
    write_reg(REG_STATUS, STATUS_RX_DR | STATUS_TX_DS | STATUS_MAX_RT);
    return result;
}

size_t nrf24_receive(uint8_t *out)
{
    size_t len = read_payload(out);
    if (len) write_reg(REG_STATUS, STATUS_RX_DR);
    return len;
}

int nrf24_queue_ack_payload(const uint8_t *payload, size_t len)
{
    if (read_reg(REG_FIFO_STATUS) & FIFO_TX_FULL) return -1;
    command(CMD_W_ACK_PAYLOAD_P0, payload, NULL, len);
    return 0;
}
