/* USART1 at 115200 baud, 8N1 (TX PA9, RX PA10) to a USB-serial adapter; interrupt-driven rings. */
#ifndef USART1_H
#define USART1_H

#include <stddef.h>
#include <stdint.h>

void usart1_init(void);
/* Queues len bytes; returns how many fit (the rest is dropped, as a full USB adapter drops them). */
size_t usart1_write(const uint8_t *data, size_t len);
/* The next received byte into *byte: 1, or 0 when none waits. */
int usart1_read(uint8_t *byte);

#endif /* USART1_H */
