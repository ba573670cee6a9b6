/* See usart1.h. */
#include "usart1.h"

#include "board.h"

#define BAUD 115200u
#define TX_SIZE 2048u /* a power of two: 0.18 s of the link at 100 Hz */
#define RX_SIZE 256u

static uint8_t tx[TX_SIZE], rx[RX_SIZE];
static volatile uint32_t tx_head, tx_tail, rx_head, rx_tail; /* head: written, tail: read; free-running */

void USART1_IRQHandler(void)
{
    uint32_t sr = USART1_SR;
    if (sr & (USART_SR_RXNE | USART_SR_ORE)) {
        uint8_t byte = (uint8_t)USART1_DR; /* also clears an overrun */
        if (rx_head - rx_tail < RX_SIZE) rx[rx_head++ % RX_SIZE] = byte;
    }
    if ((sr & USART_SR_TXE) && (USART1_CR1 & USART_CR1_TXEIE)) {
        if (tx_tail != tx_head) {
            USART1_DR = tx[tx_tail++ % TX_SIZE];
        } else {
            USART1_CR1 &= ~USART_CR1_TXEIE;
        }
    }
}

void usart1_init(void)
{
    RCC_APB2ENR |= RCC_APB2ENR_USART1EN;
    gpio_mode(GPIOA_BASE, 9, GPIO_AF_PUSH_PULL_50MHZ);
    gpio_mode(GPIOA_BASE, 10, GPIO_INPUT_PULL);
    GPIO_BSRR(GPIOA_BASE) = 1u << 10; /* pull-up: an unplugged adapter reads idle */
    USART1_BRR = CPU_HZ / BAUD;       /* APB2 at 72 MHz */
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    nvic_enable(IRQ_USART1);
}

size_t usart1_write(const uint8_t *data, size_t len)
{
    size_t n = 0;
    while (n < len && tx_head - tx_tail < TX_SIZE) tx[tx_head++ % TX_SIZE] = data[n++];
    USART1_CR1 |= USART_CR1_TXEIE;
    return n;
}

int usart1_read(uint8_t *byte)
{
    if (rx_tail == rx_head) return 0;
    *byte = rx[rx_tail++ % RX_SIZE];
    return 1;
}
