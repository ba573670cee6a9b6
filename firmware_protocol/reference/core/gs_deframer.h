/* Whole frames out of a byte stream (the bridge's serial side: uplink COMMAND frames from the host).
 *
 * The same resynchronisation as firmware_protocol/decoder.py: a candidate starts at a sync byte; one
 * with an impossible length for its type, an unknown type or a failed CRC gives up only its sync
 * byte, so a damaged frame never hides an intact frame after it. Built on gs_protocol.h only. */
#ifndef GS_DEFRAMER_H
#define GS_DEFRAMER_H

#include <stddef.h>
#include <stdint.h>

#include "gs_protocol.h"

typedef struct {
    uint8_t buf[GS_MAX_FRAME_BYTES];
    size_t n;       /* bytes in buf */
    size_t done;    /* length of the frame handed out by the last push, dropped at the next */
} gs_deframer;

static inline void gs_deframer_init(gs_deframer *d) { d->n = d->done = 0; }

/* Adds one byte. Returns the length of a complete intact frame, which is then at d->buf until the
 * next push, or 0. */
size_t gs_deframer_push(gs_deframer *d, uint8_t byte);

#endif /* GS_DEFRAMER_H */
