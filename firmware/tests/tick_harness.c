/* SPDX-License-Identifier: MIT */
/* The servo core's control iteration under the firmware bench's load, for
 * scripts/profile_tick.py: both axes PID at 20 kHz with the bench's gains,
 * a step (MODE 0) or trapezoid (MODE 1) move of 2000 counts (SHORT 1: 60
 * counts at VMAX 50 000, AMAX 5e7, which brakes inside the run), both decoders
 * counting 300 counts at 125 000 counts/s and then still, telemetry every 16
 * periods (DITHER_AMP > 0: with that square-wave dither, half-period 2 samples; KVFF_Q16,
 * KAFF_Q16 > 0: with that velocity and acceleration feed-forward).
 * The decoder registers are plain memory on the instruction-set
 * simulator: this file writes them before each tl_servo_tick. */
#include "servo_internal.h"
#include "torqueloop_regs.h"

#ifndef MODE
#define MODE 0
#endif
#ifndef SHORT
#define SHORT 0
#endif
#ifndef DITHER_AMP
#define DITHER_AMP 0
#endif
#ifndef KVFF_Q16
#define KVFF_Q16 0
#endif
#ifndef KAFF_Q16
#define KAFF_Q16 0
#endif
#ifndef NTICKS
#define NTICKS 200
#endif
#define PERIOD_CYCLES 2500u   /* 50 us at 50 MHz */
#define COUNT_CYCLES 400u     /* 8 us per count: 125 000 counts/s */
#define COUNTS 300

volatile uint32_t tohost;
static tl_servo_t s;

int main(void)
{
    TL_SYS_CLK_HZ = 50000000u;
    tl_servo_init(&s);
    uint8_t why;
    tl_param_set(&s, TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 50, &why);
    for (uint8_t ax = 0; ax < TL_AXES; ax++) {
        tl_param_set(&s, ax, TLP_P_LAW, TL_LAW_PID, &why);
        tl_param_set(&s, ax, TLP_P_KD_Q16, 655, &why);
        tl_param_set(&s, ax, TLP_P_KI_Q16, 65536 * 20, &why);
        tl_param_set(&s, ax, TLP_P_FOLLOW_LIMIT, 1000000, &why);
        if (DITHER_AMP) {
            tl_param_set(&s, ax, TLP_P_DITHER_AMP, DITHER_AMP, &why);
            tl_param_set(&s, ax, TLP_P_DITHER_HALF, 2, &why);
        }
        if (KVFF_Q16)
            tl_param_set(&s, ax, TLP_P_KVFF_Q16, KVFF_Q16, &why);
        if (KAFF_Q16)
            tl_param_set(&s, ax, TLP_P_KAFF_Q16, KAFF_Q16, &why);
        if (SHORT) {
            tl_param_set(&s, ax, TLP_P_VMAX, 50000, &why);
            tl_param_set(&s, ax, TLP_P_AMAX, 50000000, &why);
        }
    }
    tl_axes_enable(&s, (1u << TL_AXES) - 1u, &why);
    s.telem_every = 16;
    int32_t target = SHORT ? 60 : 2000;
    tl_ctl_move(&s.ax[0].c, -target, MODE != 0);
    tl_ctl_move(&s.ax[1].c, target, MODE != 0);
    uint32_t now = 1000u, edge = 0u;
    int32_t pos = 0;
    for (uint32_t n = 0; n < NTICKS; n++) {
        now += PERIOD_CYCLES;
        int32_t want = (int32_t)((now - 1000u) / COUNT_CYCLES);
        if (want > COUNTS)
            want = COUNTS;
        if (want != pos) {
            pos = want;
            edge = 1000u + (uint32_t)pos * COUNT_CYCLES;
        }
        for (uint32_t ax = 0; ax < TL_AXES; ax++) {
            uint32_t d = ax ? TL_AXIS1_BASE - TL_AXIS0_BASE : 0u;
            TL_REG32(TL_AXIS0_ENC_POS_ADDR + d) = (uint32_t)(ax ? pos : -pos);
            TL_REG32(TL_AXIS0_ENC_EDGE_TIME_ADDR + d) = edge;
            TL_REG32(TL_AXIS0_ENC_EDGE_INTERVAL_ADDR + d) = COUNT_CYCLES;
            TL_REG32(TL_AXIS0_ENC_TIMESTAMP_ADDR + d) = now;
        }
        tl_servo_tick(&s);
    }
    tohost = 0x80000000u | s.ax[0].faults | ((uint32_t)s.ax[1].faults << 16);
    return 0;
}
