/* SPDX-License-Identifier: MIT */
/* SoC integration program: everything through the generated register header.
 *  - acknowledges the reset-time safety latch (SYS.SAFETY.ESTOP);
 *  - toggles LEDR[0] from the machine-timer interrupt every HALF_PERIOD cycles
 *    (mtimecmp re-armed in the handler); the handler runs from RAM (section
 *    .ramtext, preloaded by the RAM image), so the CPU fetches from both the
 *    ROM and the RAM;
 *  - counts KEY presses from the external interrupt (INTC GPIO_KEY) and shows
 *    the count on HEX0 as raw segments;
 *  - main loop copies SW[8:0] to LEDR[9:1] with LEDR[0] from the handler,
 *    and sends 'K' on the UART for every press.
 * The test bench (tb/soc/test_soc.py) checks all of it on the pins. */
#include <stdint.h>

#include "torqueloop_regs.h"

#define HALF_PERIOD 400u   /* clock cycles between LEDR[0] toggles */

static volatile uint32_t led0;
static volatile uint32_t presses;
static uint32_t deadline_lo = 1;   /* .data: checks the ROM-to-RAM copy */

static void arm_timer(void)
{
    /* mtimecmp high first to all ones: no spurious interrupt while the low half moves. */
    TL_TIMER_MTIMECMP_HI = 0xFFFFFFFFu;
    TL_TIMER_MTIMECMP_LO = deadline_lo;
    TL_TIMER_MTIMECMP_HI = 0u;
}

__attribute__((interrupt("machine"), section(".ramtext"))) static void trap_handler(void)
{
    uint32_t cause;
    __asm__ volatile("csrr %0, mcause" : "=r"(cause));
    if (cause == 0x80000007u) {            /* machine timer */
        led0 ^= 1u;
        deadline_lo += HALF_PERIOD;
        arm_timer();
    } else if (cause == 0x8000000Bu) {     /* machine external: the INTC */
        uint32_t active = TL_INTC_ACTIVE;
        if (active & TL_INTC_PENDING_GPIO_KEY_MSK) {
            presses += 1u;
            TL_GPIO_KEY_EDGE = TL_GPIO_KEY_EDGE_KEY_MSK;
        }
        TL_INTC_PENDING = active;
    } else {
        for (;;) {                         /* unexpected trap: show it and stop */
            TL_GPIO_HEX_HI = 0x7979u;      /* "EE" */
        }
    }
}

int main(void)
{
    TL_SYS_SAFETY = TL_SYS_SAFETY_ESTOP_MSK;
    TL_GPIO_HEX_HI = 0u;
    deadline_lo += TL_TIMER_MTIME_LO + HALF_PERIOD;
    arm_timer();
    TL_INTC_PENDING = 0xFFFFFFFFu;
    TL_INTC_ENABLE = TL_INTC_PENDING_GPIO_KEY_MSK;
    __asm__ volatile("csrw mtvec, %0" : : "r"(&trap_handler));
    __asm__ volatile("csrs mie, %0" : : "r"((1u << 7) | (1u << 11)));   /* MTIE, MEIE */
    __asm__ volatile("csrs mstatus, %0" : : "r"(1u << 3));              /* MIE */

    static const uint8_t digits[10] = {0x3F, 0x06, 0x5B, 0x4F, 0x66, 0x6D, 0x7D, 0x07, 0x7F, 0x6F};
    uint32_t shown = 0u;
    for (;;) {
        TL_GPIO_LEDR = led0 | ((TL_GPIO_SW & 0x1FFu) << 1);
        uint32_t p = presses;
        TL_GPIO_HEX_LO = digits[p % 10u];
        if (p != shown && (TL_UART_STATUS & TL_UART_STATUS_TX_READY_MSK)) {
            TL_UART_TX_DATA = 'K';
            shown += 1u;
        }
    }
}
