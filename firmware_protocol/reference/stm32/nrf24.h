/* nRF24L01+ on SPI1 (CSN PA4, CE PB0; IRQ not used: STATUS is polled).
 *
 * Link: channel 76 (2.476 GHz), 1 Mbps, 0 dBm, 5-byte address "GSLNK", 2-byte CRC, auto-acknowledge
 * with up to 2 retransmissions 500 us apart, dynamic payload length (a payload is one whole frame,
 * at most 32 bytes, sent and delivered unchanged) and payloads on acknowledgements: the flight board
 * transmits (PTX); the bridge receives (PRX) and puts uplink frames on its next acknowledgements. */
#ifndef NRF24_H
#define NRF24_H

#include <stddef.h>
#include <stdint.h>

#define NRF24_MAX_PAYLOAD 32u

/* Returns 0, or -1 when no radio answers on SPI. receiver: 1 for the bridge (PRX), 0 for the board. */
int nrf24_init(int receiver);

typedef struct {
    int acknowledged;      /* the bridge received the payload */
    unsigned retransmits;  /* automatic retransmissions it took */
    size_t ack_len;        /* bytes of uplink payload that came back with the acknowledgement (0: none) */
} nrf24_result;

/* PTX: sends one payload and waits (at most ~2 ms) for its fate; ack_payload gets NRF24_MAX_PAYLOAD. */
nrf24_result nrf24_send(const uint8_t *payload, size_t len, uint8_t *ack_payload);

/* PRX: the next received payload into out (NRF24_MAX_PAYLOAD bytes), returning its length; 0 if none. */
size_t nrf24_receive(uint8_t *out);

/* PRX: queues a payload for the next acknowledgements; returns 0, or -1 when the 3-deep queue is full. */
int nrf24_queue_ack_payload(const uint8_t *payload, size_t len);

#endif /* NRF24_H */
