/* The STM32F103 registers the two ports use, from the reference manual (RM0008). Plain register
 * access: no vendor SDK, nothing to download. */
#ifndef STM32F103_H
#define STM32F103_H

#include <stdint.h>

#define REG(address) (*(volatile uint32_t *)(address))

/* RCC (RM0008 7.3) */
#define RCC_BASE 0x40021000u
#define RCC_CR REG(RCC_BASE + 0x00u)
#define RCC_CFGR REG(RCC_BASE + 0x04u)
#define RCC_APB2ENR REG(RCC_BASE + 0x18u)
#define RCC_APB1ENR REG(RCC_BASE + 0x1Cu)
#define RCC_APB1RSTR REG(RCC_BASE + 0x10u)
#define RCC_CR_HSEON (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_APB2ENR_AFIOEN (1u << 0)
#define RCC_APB2ENR_IOPAEN (1u << 2)
#define RCC_APB2ENR_IOPBEN (1u << 3)
#define RCC_APB2ENR_IOPCEN (1u << 4)
#define RCC_APB2ENR_ADC1EN (1u << 9)
#define RCC_APB2ENR_SPI1EN (1u << 12)
#define RCC_APB2ENR_USART1EN (1u << 14)
#define RCC_APB1ENR_TIM2EN (1u << 0)
#define RCC_APB1ENR_I2C1EN (1u << 21)
#define RCC_APB1ENR_BKPEN (1u << 27)
#define RCC_APB1ENR_PWREN (1u << 28)

/* Power control and the backup registers (RM0008 5.4.1, 6.4): ten 16-bit data registers, kept over
 * a reset while VBAT is powered; writable once PWR_CR.DBP is set */
#define PWR_CR REG(0x40007000u)
#define PWR_CR_DBP (1u << 8)
#define BKP_DR(n) REG(0x40006C00u + 4u * (n)) /* n = 1..10 */

/* Flash access control (RM0008 3.3.3) */
#define FLASH_ACR REG(0x40022000u)

/* GPIO (RM0008 9.2): 4 bits per pin, MODE[1:0] then CNF[1:0] */
#define GPIOA_BASE 0x40010800u
#define GPIOB_BASE 0x40010C00u
#define GPIOC_BASE 0x40011000u
#define GPIO_CRL(base) REG((base) + 0x00u)
#define GPIO_CRH(base) REG((base) + 0x04u)
#define GPIO_IDR(base) REG((base) + 0x08u)
#define GPIO_ODR(base) REG((base) + 0x0Cu)
#define GPIO_BSRR(base) REG((base) + 0x10u)
#define GPIO_BRR(base) REG((base) + 0x14u)
#define GPIO_ANALOG 0x0u
#define GPIO_INPUT_FLOATING 0x4u
#define GPIO_INPUT_PULL 0x8u
#define GPIO_OUTPUT_2MHZ 0x2u
#define GPIO_OUTPUT_50MHZ 0x3u
#define GPIO_AF_PUSH_PULL_50MHZ 0xBu
#define GPIO_AF_OPEN_DRAIN_50MHZ 0xFu

/* SPI1 (RM0008 25.5) */
#define SPI1_BASE 0x40013000u
#define SPI1_CR1 REG(SPI1_BASE + 0x00u)
#define SPI1_SR REG(SPI1_BASE + 0x08u)
#define SPI1_DR REG(SPI1_BASE + 0x0Cu)
#define SPI_SR_RXNE (1u << 0)
#define SPI_SR_TXE (1u << 1)

/* I2C1 (RM0008 26.6) */
#define I2C1_BASE 0x40005400u
#define I2C1_CR1 REG(I2C1_BASE + 0x00u)
#define I2C1_CR2 REG(I2C1_BASE + 0x04u)
#define I2C1_DR REG(I2C1_BASE + 0x10u)
#define I2C1_SR1 REG(I2C1_BASE + 0x14u)
#define I2C1_SR2 REG(I2C1_BASE + 0x18u)
#define I2C1_CCR REG(I2C1_BASE + 0x1Cu)
#define I2C1_TRISE REG(I2C1_BASE + 0x20u)
#define I2C_CR1_PE (1u << 0)
#define I2C_CR1_START (1u << 8)
#define I2C_CR1_STOP (1u << 9)
#define I2C_CR1_ACK (1u << 10)
#define I2C_CR1_SWRST (1u << 15)
#define I2C_SR1_SB (1u << 0)
#define I2C_SR1_ADDR (1u << 1)
#define I2C_SR1_BTF (1u << 2)
#define I2C_SR1_RXNE (1u << 6)
#define I2C_SR1_TXE (1u << 7)
#define I2C_SR1_AF (1u << 10)

/* USART1 (RM0008 27.6) */
#define USART1_BASE 0x40013800u
#define USART1_SR REG(USART1_BASE + 0x00u)
#define USART1_DR REG(USART1_BASE + 0x04u)
#define USART1_BRR REG(USART1_BASE + 0x08u)
#define USART1_CR1 REG(USART1_BASE + 0x0Cu)
#define USART_SR_ORE (1u << 3)
#define USART_SR_RXNE (1u << 5)
#define USART_SR_TXE (1u << 7)
#define USART_CR1_RE (1u << 2)
#define USART_CR1_TE (1u << 3)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_TXEIE (1u << 7)
#define USART_CR1_UE (1u << 13)

/* TIM2 (RM0008 15.4) */
#define TIM2_BASE 0x40000000u
#define TIM2_CR1 REG(TIM2_BASE + 0x00u)
#define TIM2_DIER REG(TIM2_BASE + 0x0Cu)
#define TIM2_SR REG(TIM2_BASE + 0x10u)
#define TIM2_EGR REG(TIM2_BASE + 0x14u)
#define TIM2_CNT REG(TIM2_BASE + 0x24u)
#define TIM2_PSC REG(TIM2_BASE + 0x28u)
#define TIM2_ARR REG(TIM2_BASE + 0x2Cu)

/* ADC1 (RM0008 11.12) */
#define ADC1_BASE 0x40012400u
#define ADC1_SR REG(ADC1_BASE + 0x00u)
#define ADC1_CR2 REG(ADC1_BASE + 0x08u)
#define ADC1_SMPR2 REG(ADC1_BASE + 0x10u)
#define ADC1_SQR3 REG(ADC1_BASE + 0x34u)
#define ADC1_DR REG(ADC1_BASE + 0x4Cu)
#define ADC_SR_EOC (1u << 1)
#define ADC_CR2_ADON (1u << 0)
#define ADC_CR2_CAL (1u << 2)
#define ADC_CR2_EXTTRIG (1u << 20)
#define ADC_CR2_SWSTART (1u << 22)
#define ADC_CR2_EXTSEL_SWSTART (7u << 17)

/* NVIC (PM0056 4.3) */
#define NVIC_ISER(n) REG(0xE000E100u + 4u * (n))
#define IRQ_TIM2 28u
#define IRQ_USART1 37u

static inline void nvic_enable(unsigned irq) { NVIC_ISER(irq / 32u) = 1u << (irq % 32u); }

#endif /* STM32F103_H */
