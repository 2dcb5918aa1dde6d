/* SPDX-License-Identifier: MIT */
/* Board-top test program: a deliberately careless firmware.
 *
 * It asks both axes for torque at once, acknowledges every cause of the
 * SoC's safety latch (e-stop, bridge faults, watchdog) over and over, echoes
 * each UART byte plus one and shows the encoder positions on the LEDs.  With
 * firmware like this, only the board-level drive interlock (SW[0] arming,
 * KEY[0], the fault inputs, the watchdog's liveness) stands between the
 * program and the motors - which is what tb/de0_cv_top checks on the pins.
 *
 * It runs from the boot ROM, so it does what the boot ROM does first: arm
 * the hardware watchdog (with a short timeout, HANG_WDOG_CYCLES, for a
 * short simulation); its loop feeds it.  While SW[8] is up it hangs with
 * interrupts off, feeding nothing; it resumes when SW[8] goes down.
 */
#include <stdint.h>

#include "torqueloop_regs.h"

#define HANG_WDOG_CYCLES 3000u   /* tb/de0_cv_top/test_de0_cv_top.py: WDOG_CYCLES */

int main(void)
{
    TL_SYS_WDOG_LOAD = HANG_WDOG_CYCLES;
    TL_SYS_WDOG_ARM = TL_SYS_WDOG_ARM_KEY_ARM_KEY;
    /* Count_max = 1: one PWM tick per clock, a 1023-clock carrier, so a
       period fits in a short simulation. */
    TL_UART_BAUD_DIV = 49u;                         /* 1 Mbaud: 50 clocks per bit, a short simulation */
    TL_AXIS0_FDIV = 1u;
    TL_AXIS1_FDIV = 1u;
    TL_AXIS0_PWM_CMD = 600u;                        /* forward: RPWM */
    TL_AXIS1_PWM_CMD = (uint32_t)(-400) & 0x7FFu;   /* reverse: LPWM */
    TL_AXIS0_PWM_CTRL = 1u;                         /* ENABLE, coast when safe */
    TL_AXIS1_PWM_CTRL = 1u;
    for (;;) {
        TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_A;
        TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_B;
        __asm__ volatile("csrc mstatus, %0" : : "r"(1u << 3));   /* interrupts off (they are never on) */
        while (TL_GPIO_SW & (1u << 8)) {
        }
        TL_SYS_SAFETY = TL_SYS_SAFETY_ESTOP_MSK | TL_SYS_SAFETY_FAULT0_MSK | TL_SYS_SAFETY_FAULT1_MSK |
                        TL_SYS_SAFETY_WDOG_MSK;
        uint32_t rx = TL_UART_RX_DATA;
        if (rx & TL_UART_RX_DATA_VALID_MSK)
            TL_UART_TX_DATA = (rx + 1u) & 0xFFu;
        /* Low nibble of each encoder position on LEDR[3:0] / LEDR[7:4]. */
        TL_GPIO_LEDR = (TL_AXIS0_ENC_POS & 0xFu) | ((TL_AXIS1_ENC_POS & 0xFu) << 4);
    }
}
