/* The core's AHF on a Cortex-M3 under QEMU (lm3s6965evb), for its cost and to check it against the
 * host build: steps through the samples of ahf_input.h (generated: float bits of gyro, accelerometer
 * and dt) and prints, per sample over semihosting, the status and the bits of q and lambda.
 * mark() brackets each step, so a QEMU instruction trace counts exactly the step's instructions. */
#include <stdint.h>
#include <string.h>

#include "ahf_input.h" /* GS_INPUT_SAMPLES, gs_input[GS_INPUT_SAMPLES][7] */
#include "gs_ahf.h"

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;

/* ARM semihosting (Thumb): operation in r0, argument in r1, BKPT 0xAB. */
static void semihost(uint32_t op, const void *arg)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
}

static char line[96];
static unsigned line_len;

static void put_hex(uint32_t v)
{
    for (int shift = 28; shift >= 0; shift -= 4) line[line_len++] = "0123456789abcdef"[(v >> shift) & 0xFu];
    line[line_len++] = ' ';
}

static uint32_t bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float from_bits(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

__attribute__((noinline)) void mark(void) { __asm__ volatile(""); }

int main(void)
{
    gs_ahf_settings settings;
    gs_ahf filter;
    gs_ahf_default_settings(&settings);
    gs_ahf_init(&filter, &settings, 0);
    for (unsigned k = 0; k < GS_INPUT_SAMPLES; k++) {
        float gyr[3], acc[3];
        for (int i = 0; i < 3; i++) {
            gyr[i] = from_bits(gs_input[k][i]);
            acc[i] = from_bits(gs_input[k][3 + i]);
        }
        mark();
        unsigned status = gs_ahf_step(&filter, gyr, acc, from_bits(gs_input[k][6]));
        mark();
        line_len = 0;
        put_hex(status);
        for (int i = 0; i < 4; i++) put_hex(bits(filter.q[i]));
        put_hex(bits(filter.lam));
        line[line_len - 1] = '\n';
        line[line_len] = '\0';
        semihost(0x04u, line); /* SYS_WRITE0 */
    }
    return 0;
}

void Reset_Handler(void)
{
    uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) *dst++ = *src++;
    for (uint32_t *dst = &_sbss; dst < &_ebss;) *dst++ = 0;
    main();
    semihost(0x18u, (const void *)0x20026u); /* SYS_EXIT, ADP_Stopped_ApplicationExit */
    for (;;) {}
}

void Default_Handler(void)
{
    semihost(0x18u, (const void *)0x20023u); /* SYS_EXIT, ADP_Stopped_RunTimeErrorUnknown */
    for (;;) {}
}

__attribute__((section(".isr_vector"), used)) void (*const vectors[16])(void) = {
    (void (*)(void))&_estack, Reset_Handler, Default_Handler, Default_Handler, Default_Handler, Default_Handler,
    Default_Handler, 0, 0, 0, 0, Default_Handler, Default_Handler, 0, Default_Handler, Default_Handler,
};
