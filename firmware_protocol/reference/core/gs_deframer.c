/* See gs_deframer.h. */
#include "gs_deframer.h"

#include <string.h>

static void drop(gs_deframer *d, size_t count)
{
    memmove(d->buf, d->buf + count, d->n - count);
    d->n -= count;
}

size_t gs_deframer_push(gs_deframer *d, uint8_t byte)
{
    if (d->done) {
        drop(d, d->done);
        d->done = 0;
    }
    d->buf[d->n++] = byte;
    for (;;) {
        size_t start = 0;
        while (start < d->n && d->buf[start] != GS_SYNC) start++;
        drop(d, start);
        if (d->n < GS_HEADER_BYTES) return 0;
        int size = gs_payload_size(d->buf[2]);
        if (size < 0 || d->buf[1] != (uint8_t)size) {
            drop(d, 1);
            continue;
        }
        size_t total = (size_t)size + GS_HEADER_BYTES + GS_CRC_BYTES;
        if (d->n < total) return 0;
        if (gs_check_frame(d->buf, total) < 0) {
            drop(d, 1);
            continue;
        }
        d->done = total;
        return total;
    }
}
