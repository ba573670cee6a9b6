/* What both ports share on the Blue Pill: 72 MHz clock, the LED, a microsecond clock, SPI1. */
#ifndef BOARD_H
#define BOARD_H

#include <stddef.h>
#include <stdint.h>

#include "stm32f103.h"

#define CPU_HZ 72000000u

/* Configures one pin (4-bit GPIO_* mode) of port base 0-15. */
void gpio_mode(uint32_t base, unsigned pin, uint32_t mode);

/* 72 MHz from the 8 MHz crystal (HSE x 9), APB1 36 MHz, APB2 72 MHz; GPIO A, B, C clocked; LED off. */
void board_init(void);

/* The LED on PC13 (lit when the pin is low). */
void led(int on);
void led_toggle(void);

/* Free-running microseconds since board_init (TIM2 at 1 MHz, extended to 32 bits; wraps every 71.6 min). */
uint32_t micros(void);
void delay_us(uint32_t us);

/* SPI1, mode 0, 9 MHz: SCK PA5, MISO PA6, MOSI PA7 (chip selects are the caller's). */
void spi1_init(void);
uint8_t spi1_transfer(uint8_t byte);

#endif /* BOARD_H */
