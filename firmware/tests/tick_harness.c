/* SPDX-License-Identifier: MIT */
/* The servo core's control iteration under the firmware bench's load, for
 * scripts/profile_tick.py: both axes PID at 20 kHz with the bench's gains,
 * a step (MODE 0) or trapezoid (MODE 1) move of 2000 counts (SHORT 1: 60
 * counts at VMAX 50 000, AMAX 5e7, which brakes inside the run), both decoders
 * counting 300 counts at 125 000 counts/s and then still (the telemetry's
 * cadence is the main loop's, tl_servo_telemetry_due: not here; DITHER_AMP > 0:
 * with that square-wave dither, half-period 2 samples; KVFF_Q16, KAFF_Q16 > 0:
 * with that velocity and acceleration feed-forward; TICK0: the period count to
 * start from, which moves the runaway checks' phases against the moves).
 * MODE 2, the board image's case (experiment.run_fast_loop with trapezoids):
 * Table 1's PID gains, the parameters' defaults otherwise (VMAX, AMAX, the
 * runaway and following checks; the link watchdog's the longest, nothing
 * feeds it here), VEL_MODE 1, a screw turn each way (braking planned after
 * about 20 000 periods, both axes in the same one), and the
 * decoders driven by a crude closed-loop motor (a first-order speed response to
 * the command above a breakaway, in integers): slow, sparse counts while the
 * trapezoid speeds up, each after silent periods, with the commands the
 * integrator builds against the breakaway.  It exercises the paths, it is not
 * the plant (the bench's Verilator run with the real plant has the last word).
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
#ifndef TICK0
#define TICK0 0   /* the period count the run starts from: which runaway check each period runs */
#endif
#define PERIOD_CYCLES 2500u   /* 50 us at 50 MHz */
#define COUNT_CYCLES 400u     /* 8 us per count: 125 000 counts/s */
#define COUNTS 300

volatile uint32_t tohost;
static tl_servo_t s;

/* The decoder registers of axis ax as the iteration will read them. */
static void write_decoder(uint32_t ax, int32_t pos, uint32_t edge, uint32_t interval, uint32_t now)
{
    uint32_t d = ax ? TL_AXIS1_BASE - TL_AXIS0_BASE : 0u;
    TL_REG32(TL_AXIS0_ENC_POS_ADDR + d) = (uint32_t)pos;
    TL_REG32(TL_AXIS0_ENC_EDGE_TIME_ADDR + d) = edge;
    TL_REG32(TL_AXIS0_ENC_EDGE_INTERVAL_ADDR + d) = interval;
    TL_REG32(TL_AXIS0_ENC_TIMESTAMP_ADDR + d) = now;
}

#if MODE == 2
/* Table 1's PID gains (KP_UNM_RAD ...) and each axis's no-load speed at full
 * command (counts/s), passed by scripts/profile_tick.py from
 * torqueloop/spec/system.toml: TABLE1_PID {kp0, kd0, ki0, kp1, kd1, ki1},
 * NO_LOAD_CPS {cps0, cps1}. */
#if !defined(TABLE1_PID) || !defined(NO_LOAD_CPS)
#error "MODE 2 needs TABLE1_PID and NO_LOAD_CPS (scripts/profile_tick.py passes them)"
#endif
/* The crude motor of MODE 2, per axis: speed v (counts/s q16) approaching
 * cps (|cmd| - BREAK) / 1023 in the command's direction with time constant
 * TAU_US (no motion at or below BREAK once the speed has decayed), position in
 * counts q32; an edge's time is interpolated within the period. */
#define M_BREAK 120
#define M_TAU_US 30000
typedef struct { int64_t pos_q32, v_q16; uint32_t edge, interval; } motor_t;

static void motor_period(motor_t *m, int32_t cps, int32_t cmd, uint32_t now)
{
    int32_t mag = cmd < 0 ? -cmd : cmd;
    int64_t vss = mag > M_BREAK ? ((int64_t)cps * (mag - M_BREAK) << 16) / 1023 : 0;
    if (cmd < 0)
        vss = -vss;
    m->v_q16 += (vss - m->v_q16) * 50 / M_TAU_US;
    if (vss == 0 && (m->v_q16 < (1 << 16) && m->v_q16 > -(1 << 16)))
        m->v_q16 = 0;
    int64_t before = m->pos_q32 >> 32;
    m->pos_q32 += (m->v_q16 << 16) / 20000;            /* 50 us of speed, counts q32 */
    int64_t after = m->pos_q32 >> 32;
    if (after != before && m->v_q16 != 0) {
        /* the last crossing: the fraction of a count past it over the speed, in clocks */
        int64_t av = m->v_q16 < 0 ? -m->v_q16 : m->v_q16;
        uint64_t frac = (uint64_t)(m->v_q16 > 0 ? m->pos_q32 - (after << 32) : ((after + 1) << 32) - m->pos_q32);
        uint64_t ago = (frac >> 16) * 50000000u / (uint64_t)av;
        uint32_t e = now - (uint32_t)(ago > 2499u ? 2499u : ago);
        int64_t n = after > before ? after - before : before - after;
        m->interval = n > 1 ? (uint32_t)(2500 / n) : e - m->edge;
        m->edge = e;
    }
}
#endif

int main(void)
{
    TL_SYS_CLK_HZ = 50000000u;
    tl_servo_init(&s);
    uint8_t why;
    tl_param_set(&s, TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 50, &why);
#if MODE == 2
    static const int32_t gains[2 * 3] = TABLE1_PID, cps[2] = NO_LOAD_CPS;
    tl_param_set(&s, TLP_GLOBAL_AXIS, TLP_P_LINK_TIMEOUT_MS, 60000, &why);   /* nothing feeds the link here */
    for (uint8_t ax = 0; ax < TL_AXES; ax++) {
        tl_param_set(&s, ax, TLP_P_LAW, TL_LAW_PID, &why);
        tl_param_set(&s, ax, TLP_P_KP_UNM_RAD, gains[3 * ax], &why);
        tl_param_set(&s, ax, TLP_P_KD_UNMS_RAD, gains[3 * ax + 1], &why);
        tl_param_set(&s, ax, TLP_P_KI_UNM_RADS, gains[3 * ax + 2], &why);
        tl_param_set(&s, ax, TLP_P_VEL_MODE, 1, &why);
    }
    tl_axes_enable(&s, (1u << TL_AXES) - 1u, &why);
    s.ticks = TICK0;
    tl_ctl_move(&s.ax[0].c, 8400, true);
    tl_ctl_move(&s.ax[1].c, -8400, true);
    motor_t m[2] = {{0, 0, 0u, 2500u}, {0, 0, 0u, 2500u}};
    uint32_t now = 1000u;
    for (uint32_t n = 0; n < NTICKS; n++) {
        now += PERIOD_CYCLES;
        for (uint32_t ax = 0; ax < TL_AXES; ax++) {
            motor_period(&m[ax], cps[ax], s.ax[ax].cmd, now);
            write_decoder(ax, (int32_t)(m[ax].pos_q32 >> 32), m[ax].edge, m[ax].interval, now);
        }
        tl_servo_tick(&s);
    }
#else
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
    s.ticks = TICK0;
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
        for (uint32_t ax = 0; ax < TL_AXES; ax++)
            write_decoder(ax, ax ? pos : -pos, edge, COUNT_CYCLES, now);
        tl_servo_tick(&s);
    }
#endif
    tohost = 0x80000000u | s.ax[0].faults | ((uint32_t)s.ax[1].faults << 16);
    return 0;
}
