/* SPDX-License-Identifier: MIT */
/* The checks the control iteration makes every period (docs/safety.md), inline
 * into tl_servo_tick (servo.c): what the SoC safety latch bits mean for an axis,
 * the soft limits, the runaway check, and which sides an axis must not be driven
 * toward.  safety.c holds what runs outside the iteration (latch, enable, clear). */
#ifndef TL_SAFETY_H
#define TL_SAFETY_H

#include "servo_internal.h"

#define LATCH_BITS (TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG)
_Static_assert(TL_HAL_LIM_NEG == TLP_LIMIT_NEG && TL_HAL_LIM_POS == TLP_LIMIT_POS, "limit bits");

/* Faults the SoC safety latch bits mean for axis i: its own bridge bit always
 * (a bridge fault is a fault of that axis whatever it was doing), the shared
 * e-stop and watchdog bits for an axis they stopped (enabled). */
static inline __attribute__((always_inline)) uint16_t latch_bridge(uint32_t i, uint32_t safety)
{
    return (safety & (i == 0u ? TL_HAL_SAFE_FAULT0 : TL_HAL_SAFE_FAULT1)) ? TLP_FAULT_BRIDGE : 0u;
}
static inline __attribute__((always_inline)) uint16_t latch_enabled(uint32_t safety)
{
    return (uint16_t)(((safety & TL_HAL_SAFE_ESTOP) ? TLP_FAULT_ESTOP : 0u) |
                      ((safety & TL_HAL_SAFE_WDOG) ? TLP_FAULT_HW_SAFE : 0u));
}
/* The soft-limit side the position is beyond (SOFT_MIN <= SOFT_MAX: at most one). */
static inline __attribute__((always_inline)) uint8_t soft_side(const tl_axis_t *a)
{
    return a->pos < pv(a, TLP_P_SOFT_MIN) ? TLP_LIMIT_NEG : (a->pos > pv(a, TLP_P_SOFT_MAX) ? TLP_LIMIT_POS : 0u);
}

/* Runaway / encoder loss.  A command of STALL_CMD or more must, within
 * STALL_MS, either move the position past a reference in its direction or
 * raise the velocity in its direction by STALL_DV_Q8 over a reference; each
 * time it does, the references move up to where the axis is.  An axis that
 * accelerates, cruises, or is braked from the other direction satisfies it
 * every few periods; a frozen encoder, one that counts the wrong way (the
 * measured motion runs away against the command) or one channel flickering
 * never does.  A compare and a counter per period: no division, no history. */
#define STALL_DV_Q8 (20 * 256)   /* 20 counts/s */
static inline __attribute__((always_inline)) uint16_t stall_check(tl_axis_t *a)
{
    /* everything it reads first: the tests would otherwise wait for the loads (2 cycles on tl_cpu_pipe) */
    int32_t lim = pv(a, TLP_P_STALL_CMD), cmd = a->cmd, ref = a->stall_ref, vr = a->stall_vel_q8, v = a->c.vel_q8;
    int8_t sdir = a->stall_dir;
    uint32_t ticks = a->stall_ticks, limit = a->stall_limit_ticks;
    int8_t dir = cmd >= lim ? 1 : (cmd <= -lim ? -1 : 0);
    if (TL_UNLIKELY(dir == 0 || dir != sdir)) {
        a->stall_dir = dir;
        a->stall_ref = a->pos;
        a->stall_vel_q8 = v;
        a->stall_ticks = 0;
        return 0;
    }
    /* each reference only ever moves on in dir */
    int32_t moved = (int32_t)((uint32_t)a->pos - (uint32_t)ref);
    /* the speed's rise in dir, 32-bit: when v is past the reference in dir the difference
     * is below 2^32, exact as an unsigned one */
    bool progress = false;
    if (dir > 0 ? moved > 0 : moved < 0) {
        a->stall_ref = a->pos;
        progress = true;
    }
    if (dir > 0 ? v > vr && (uint32_t)v - (uint32_t)vr > (uint32_t)STALL_DV_Q8
                : v < vr && (uint32_t)vr - (uint32_t)v > (uint32_t)STALL_DV_Q8) {
        a->stall_vel_q8 = v;
        progress = true;
    }
    if (progress) {
        a->stall_ticks = 0;
        return 0;
    }
    a->stall_ticks = ++ticks;
    return ticks >= limit ? TLP_FAULT_RUNAWAY : 0u;
}

/* The switch homing is looking for does not trip a limit fault. */
static inline __attribute__((always_inline)) uint8_t home_switch(const tl_axis_t *a)
{
    if (a->home != TLP_HOME_STATE_HOMING)
        return 0;
    return a->home_dir < 0 ? TLP_LIMIT_NEG : TLP_LIMIT_POS;
}

/* What the SoC safety word means this period, worked out once for both axes. */
typedef struct {
    uint32_t safety;
    uint16_t all;        /* faults of every axis: the e-stop input */
    uint16_t enabled;    /* faults of an enabled axis: the latched e-stop and watchdog bits */
    bool link;           /* the link watchdog expired (enabled axes) */
    uint32_t ticks;      /* this period's number ... */
    uint32_t odd;        /* ... and tl_servo_t.runaway_odd: axis i's runaway checks skip periods with (ticks + i) & odd */
} tick_faults_t;

/* Every check of one axis for this period; returns the faults that tripped.
 * *out: the soft-limit sides the position is beyond (enabled axes only). */
static inline __attribute__((always_inline)) uint16_t axis_checks(tl_axis_t *a, uint32_t i,
                                                                  const tl_enc_sample_t *e,
                                                                  const tick_faults_t *t, uint8_t *out)
{
    /* read first: the tests below would otherwise wait for their loads (2 cycles on tl_cpu_pipe);
     * nothing before the tests changes them */
    uint32_t illegal_seen = a->illegal_seen;
    uint8_t limit_mask = a->limit_mask;
    bool enabled = a->enabled;
    /* latch_faults, the e-stop input and the bridge input */
    uint16_t f = t->all | latch_bridge(i, t->safety);
    if (TL_UNLIKELY(e->bridge_fault))
        f |= TLP_FAULT_BRIDGE;
    if (TL_UNLIKELY(e->illegal != illegal_seen)) {
        f |= TLP_FAULT_ENCODER;
        a->illegal_seen = e->illegal;
    }
    /* the switches when LIMIT_SW is set, by its derived mask: no branch */
    uint8_t lim = (uint8_t)(e->limits & limit_mask);
    a->limits = lim;
    if (TL_UNLIKELY(lim)) {
        lim &= (uint8_t)~home_switch(a);
        if (lim & TLP_LIMIT_NEG)
            f |= TLP_FAULT_LIMIT_NEG;
        if (lim & TLP_LIMIT_POS)
            f |= TLP_FAULT_LIMIT_POS;
    }
    /* not marked unlikely: the return's block then stays in line and the branch reaches it
     * directly, where a cold block at the iteration's far end costs the enabled axis a branch
     * over a jump (out of a conditional branch's 4 KiB reach: 3 cycles on tl_cpu_pipe) */
    if (!enabled)
        return f;
    f |= t->enabled;
    if (TL_UNLIKELY((t->safety & TL_HAL_SAFE_FORCED) && f == 0u))
        f |= TLP_FAULT_HW_SAFE;   /* forced off by a cause not seen above */
    if (TL_UNLIKELY(t->link))
        f |= TLP_FAULT_LINK;
    /* following error |sp - pos| > FOLLOW_LIMIT, sp in counts (int32 range: it lies between
     * positions and targets), the difference in 33 bits */
    int32_t sp = (int32_t)(a->c.sp_q16 >> 16);
    uint32_t fl = (uint32_t)pv(a, TLP_P_FOLLOW_LIMIT);
    uint32_t ad = sp >= a->pos ? (uint32_t)sp - (uint32_t)a->pos : (uint32_t)a->pos - (uint32_t)sp;
    if (TL_UNLIKELY(ad > fl))
        f |= TLP_FAULT_FOLLOWING;
    /* Outside the soft limits: a fault unless the axis was enabled out there
     * (it may then only come back in); back inside, that allowance ends. */
    uint8_t o = soft_side(a);
    *out = o;
    if (TL_UNLIKELY(a->recover | o)) {
        a->recover &= o;
        if (o & (uint8_t)~a->recover)
            f |= TLP_FAULT_SOFT_LIMIT;
    }
    if (t->odd & (t->ticks + i)) {
        /* The runaway checks' off period (below TL_RUNAWAY_EVERY_OTHER_BELOW_US they run every
         * other period, the axes in turn).  A command against the direction a check follows
         * (of the other sign, or 0 after a negative one) restarts that check at its next run,
         * as the reversal would have here; one that only dipped below the check's threshold
         * in this period does not (docs/safety.md, "Runaway at 20 kHz"). */
        int32_t c = a->cmd;
        int8_t sd = a->stall_dir, ed = a->enc_dir;
        if (TL_UNLIKELY(sd != 0 && (c ^ sd) < 0))
            a->stall_dir = 0;
        if (TL_UNLIKELY(ed != 0 && (c ^ ed) < 0))
            a->enc_dir = 0;
        return f;
    }
    return f | stall_check(a) | enc_check(a, pv(a, TLP_P_ENC_CMD0), pv(a, TLP_P_ENC_SLACK));
}

/* Sides toward which the axis must not be driven: a latched limit fault, a
 * limit switch open now, or soft, the soft-limit side the position is beyond. */
static inline __attribute__((always_inline)) uint8_t blocked_with(const tl_axis_t *a, uint16_t faults, uint8_t soft)
{
    return (uint8_t)(a->limits | soft | ((faults & TLP_FAULT_LIMIT_NEG) ? TLP_LIMIT_NEG : 0u) |
                     ((faults & TLP_FAULT_LIMIT_POS) ? TLP_LIMIT_POS : 0u));
}
#endif
