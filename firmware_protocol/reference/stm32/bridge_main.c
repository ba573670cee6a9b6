/* The radio bridge: nRF24L01+ receiver -> USART1 -> USB-serial adapter -> the ground station.
 *
 * Downlink payloads (one frame each) go to the serial port byte for byte, unchanged; the ground
 * station's decoder does all checking. Uplink bytes from the serial port are cut into whole frames
 * (gs_deframer: sync, length, CRC) and each rides on the radio's next acknowledgements to the
 * flight board.
 *
 * LED (PC13): toggles with every payload received (a steady glow at 100 Hz); off: nothing heard for
 * half a second; steady on: no radio. */
#include "board.h"
#include "gs_deframer.h"
#include "nrf24.h"
#include "usart1.h"

int main(void)
{
    board_init();
    usart1_init();
    if (nrf24_init(1) != 0) {
        led(1);
        for (;;) {}
    }
    gs_deframer uplink;
    gs_deframer_init(&uplink);
    uint8_t payload[NRF24_MAX_PAYLOAD];
    uint32_t last_heard = micros();
    for (;;) {
        size_t len;
        while ((len = nrf24_receive(payload)) != 0) {
            usart1_write(payload, len);
            led_toggle();
            last_heard = micros();
        }
        if (micros() - last_heard > 500000u) led(0);
        uint8_t byte;
        while (usart1_read(&byte)) {
            size_t frame = gs_deframer_push(&uplink, byte);
            if (frame) nrf24_queue_ack_payload(uplink.buf, frame); /* a full queue drops it: no ACK comes back */
        }
    }
}
