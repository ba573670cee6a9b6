/* See board.h. */
#include "board.h"

static volatile uint32_t micros_high; /* TIM2 overflows: the upper 16 bits of micros() */

void gpio_mode(uint32_t base, unsigned pin, uint32_t mode)
{
    volatile uint32_t *cr = pin < 8u ? &GPIO_CRL(base) : &GPIO_CRH(base);
    unsigned shift = (pin % 8u) * 4u;
    *cr = (*cr & ~(0xFu << shift)) | (mode << shift);
}

void TIM2_IRQHandler(void)
{
    TIM2_SR = 0;
    micros_high++;
}

void board_init(void)
{
    RCC_CR |= RCC_CR_HSEON;
    while (!(RCC_CR & RCC_CR_HSERDY)) {}
    FLASH_ACR = 0x12u; /* prefetch on, two wait states (48-72 MHz) */
    /* PLL from HSE x 9; APB1 /2 (36 MHz max), APB2 /1, ADC /6 (12 MHz, 14 MHz max) */
    RCC_CFGR = (7u << 18) | (1u << 16) | (4u << 8) | (2u << 14);
    RCC_CR |= RCC_CR_PLLON;
    while (!(RCC_CR & RCC_CR_PLLRDY)) {}
    RCC_CFGR |= 2u; /* system clock from the PLL */
    while ((RCC_CFGR & 0xCu) != 0x8u) {}

    RCC_APB2ENR |= RCC_APB2ENR_AFIOEN | RCC_APB2ENR_IOPAEN | RCC_APB2ENR_IOPBEN | RCC_APB2ENR_IOPCEN;
    RCC_APB1ENR |= RCC_APB1ENR_TIM2EN;
    gpio_mode(GPIOC_BASE, 13, GPIO_OUTPUT_2MHZ);
    led(0);

    /* TIM2 counts microseconds: its clock is 2 x APB1 = 72 MHz */
    TIM2_PSC = CPU_HZ / 1000000u - 1u;
    TIM2_ARR = 0xFFFFu;
    TIM2_EGR = 1u; /* load the prescaler now */
    TIM2_SR = 0;
    TIM2_DIER = 1u; /* update interrupt: the upper half */
    nvic_enable(IRQ_TIM2);
    TIM2_CR1 = 1u;
}

void led(int on)
{
    if (on) {
        GPIO_BRR(GPIOC_BASE) = 1u << 13;
    } else {
        GPIO_BSRR(GPIOC_BASE) = 1u << 13;
    }
}

void led_toggle(void) { led((GPIO_ODR(GPIOC_BASE) >> 13) & 1u); }

uint32_t micros(void)
{
    uint32_t high, low;
    do { /* the overflow interrupt may run between the two reads: read again */
        high = micros_high;
        low = TIM2_CNT;
    } while (high != micros_high);
    return (high << 16) | low;
}

void delay_us(uint32_t us)
{
    uint32_t start = micros();
    while (micros() - start < us) {}
}

void spi1_init(void)
{
    RCC_APB2ENR |= RCC_APB2ENR_SPI1EN;
    gpio_mode(GPIOA_BASE, 5, GPIO_AF_PUSH_PULL_50MHZ);
    gpio_mode(GPIOA_BASE, 6, GPIO_INPUT_FLOATING);
    gpio_mode(GPIOA_BASE, 7, GPIO_AF_PUSH_PULL_50MHZ);
    /* master, f_PCLK2 / 8 = 9 MHz (the nRF24L01+ takes up to 10), software NSS, enabled */
    SPI1_CR1 = (1u << 2) | (2u << 3) | (1u << 8) | (1u << 9) | (1u << 6);
}

uint8_t spi1_transfer(uint8_t byte)
{
    while (!(SPI1_SR & SPI_SR_TXE)) {}
    SPI1_DR = byte;
    while (!(SPI1_SR & SPI_SR_RXNE)) {}
    return (uint8_t)SPI1_DR;
}
