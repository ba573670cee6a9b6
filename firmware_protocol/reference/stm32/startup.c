/* Reset and the vector table of the STM32F103 (RM0008 10.1.2): copy .data, zero .bss, run main. */
#include <stdint.h>

extern uint32_t _estack, _sidata, _sdata, _edata, _sbss, _ebss;
int main(void);

void Default_Handler(void)
{
    for (;;) {}
}

void Reset_Handler(void)
{
    uint32_t *src = &_sidata;
    for (uint32_t *dst = &_sdata; dst < &_edata;) *dst++ = *src++;
    for (uint32_t *dst = &_sbss; dst < &_ebss;) *dst++ = 0;
    main();
    for (;;) {}
}

/* The handlers a port defines; the others stay in Default_Handler. */
void TIM2_IRQHandler(void) __attribute__((weak, alias("Default_Handler")));
void USART1_IRQHandler(void) __attribute__((weak, alias("Default_Handler")));

#define D Default_Handler
#define D4 D, D, D, D
/* 16 Cortex-M3 exceptions, then the 60 interrupts of the medium-density parts */
__attribute__((section(".isr_vector"), used)) void (*const vectors[16 + 60])(void) = {
    (void (*)(void))&_estack, Reset_Handler, D, D, D, D, D, 0, 0, 0, 0, D, D, 0, D, D,
    D4, D4, D4, D4, D4, D4, D4,             /* IRQ 0-27 */
    TIM2_IRQHandler,                        /* IRQ 28 */
    D4, D4,                                 /* IRQ 29-36 */
    USART1_IRQHandler,                      /* IRQ 37 */
    D, D, D4, D4, D4, D4, D4,               /* IRQ 38-59 */
};
