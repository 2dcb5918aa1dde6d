/* SPDX-License-Identifier: MIT */
/* A firmware that hangs (scripts/benches/bench_safety.py): a RAM image like
 * any upload, started after the boot ROM (stub) armed the hardware watchdog.
 * It drives axis 0 forward at 30 % and feeds the watchdog until mtime reaches
 * HANG_AT_CYCLES, then turns interrupts off and spins without feeding it -
 * what a firmware stuck in a loop does.  The bench measures at the pins how
 * long the bridge keeps being driven. */
#include <stdint.h>

#include "torqueloop_regs.h"

#ifndef HANG_AT_CYCLES
#define HANG_AT_CYCLES 2000000u   /* 40 ms */
#endif

int main(void)
{
    TL_AXIS0_FDIV = 2u;                    /* 24.4 kHz */
    TL_AXIS0_PWM_CMD = 300u;
    TL_AXIS0_PWM_CTRL = TL_AXIS_PWM_CTRL_ENABLE_MSK | TL_AXIS_PWM_CTRL_LIMIT_EN_MSK;
    while (TL_TIMER_MTIME_LO < HANG_AT_CYCLES) {
        TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_A;
        TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_B;
        TL_SYS_SAFETY = TL_SYS_SAFETY_ESTOP_MSK;   /* the reset latch, acknowledged */
    }
    __asm__ volatile("csrc mstatus, %0" : : "r"(1u << 3));
    for (;;) {
    }
}
