/* SPDX-License-Identifier: MIT */
/* One sample of control.c's axis control (velocity, profile, law), as an
 * always-inline function: control.c's tl_ctl_step is this, and the servo's
 * control iteration (servo.c) inlines it into each axis, so the two axes run
 * without calls and register saves (docs/firmware.md, "Timing").  Only
 * control.c and servo.c include it. */
#ifndef TL_CONTROL_STEP_H
#define TL_CONTROL_STEP_H

#include "control.h"

static inline int64_t clamp64(int64_t v, int64_t lo, int64_t hi) { return v < lo ? lo : (v > hi ? hi : v); }
/* x < 0 from the high word alone. */
static inline bool neg64(int64_t x) { return (int32_t)((uint64_t)x >> 32) < 0; }
/* Counts between two decoder readings: the 32-bit counter wraps, so the
 * difference is taken modulo 2^32 (a signed subtraction would overflow). */
static inline int32_t count_diff(int32_t a, int32_t b) { return (int32_t)((uint32_t)a - (uint32_t)b); }

/* x, hidden from the optimiser: n - (n / d) * d stays a multiply (4 cycles on
 * this CPU) instead of becoming a second divide (35). */
static inline uint32_t opaque(uint32_t x)
{
    __asm__("" : "+r"(x));
    return x;
}

/* Trapezoidal profile (docs/firmware.md, "Fourth pass"; torqueloop/oracles/servo.py _profile is
 * its definition): each sample the speed toward the target rises by at most a and never exceeds
 * vmax while the braking surplus E = d - S(v) stays >= 0, S(v) = (v - a) + (v - 2a) + ... the
 * distance braking by a covers after a sample at speed v - so braking from the new speed still
 * stops short of the target.  E is carried from sample to sample: E(v + a) = E(v) - (v + a) - v,
 * cruising E(vmax) = E(vmax) - vmax; no product and no quotient per sample.  When it would go
 * negative, the axis brakes from the last speed b by a per sample, and the rest R = E = d - S(b)
 * (< 2b + a) goes into the braking as at most two more speeds p1 >= p2 (p2 <= b), merged in
 * descending order: no sample changes the speed by more than a, every speed is positive and the
 * speeds sum to d, so the last one lands exactly on the target.  A new target, vmax or amax plans
 * again (profile_plan): moving away, it speeds up toward the target (E = d); unable to stop in
 * time (E < 0), it brakes by a past the target (E stays d - S(v)) and comes back. */
static inline uint64_t stop_sum(uint32_t v, uint32_t a)
{
    uint32_t m = v ? (v - 1u) / a : 0u;              /* the positive terms v - j a, j = 1 .. m */
    return ((uint64_t)m * (2u * v - a * (m + 1u))) >> 1;   /* m v - a m (m + 1) / 2; 2v < 2^31 */
}

/* The braking surplus E, and E stored as prof_eres + prof_e32 with as much of it as fits in
 * 0 <= prof_e32 < 2^31 (all of a negative E in prof_eres). */
static inline int64_t profile_e(const tl_ctl_t *c) { return c->prof_eres + c->prof_e32; }
static inline void profile_set_e(tl_ctl_t *c, int64_t e)
{
    int32_t lo = e < 0 ? 0 : (e > 0x7FFFFFFF ? 0x7FFFFFFF : (int32_t)e);
    c->prof_e32 = lo;
    c->prof_eres = e - lo;
}

/* The profile at rest on the set-point (no speed, no acceleration). */
static inline __attribute__((always_inline)) void profile_rest(tl_ctl_t *c)
{
    c->prof_v_q16 = 0;
    c->prof_a_q16 = 0;
    c->moving = false;
}

/* The sample's speed w (toward the target; s: 0 up, -1 down) into the set-point. */
static inline __attribute__((always_inline)) void profile_out(tl_ctl_t *c, int32_t w, int32_t s)
{
    w = (w ^ s) - s;
    c->prof_a_q16 = w - c->prof_v_q16;   /* at most a, or a drop to a lowered vmax: fits 31 bits */
    c->prof_v_q16 = w;
    c->sp_q16 += w;
}

/* Braking: the next of the braking speeds b - a, b - 2a, ... and the pending p1 >= p2 in
 * descending order, into w; true when nothing is left after it: the sample lands. */
static inline __attribute__((always_inline)) bool profile_brake(tl_ctl_t *c, int32_t a, int32_t *w)
{
    int32_t nb = (int32_t)c->prof_b - a;
    uint32_t p1 = c->prof_p1;
    *w = 0;
    bool pending = (p1 != 0u) & ((int32_t)p1 >= nb);   /* & not &&: one branch */
    if (TL_UNLIKELY(pending)) {                      /* the larger pending speed, in its place */
        *w = (int32_t)p1;
        c->prof_p1 = p1 = c->prof_p2;
        c->prof_p2 = 0u;
    } else if (nb > 0) {
        *w = nb;
        c->prof_b = (uint32_t)nb;
    }
    return p1 == 0u && (int32_t)c->prof_b <= a;
}

static inline __attribute__((always_inline)) void profile(tl_ctl_t *c)
{
    int32_t s = c->prof_s;                           /* toward the target: 0 up, -1 down */
    int32_t a = c->d.amax_q16, vmax = c->d.vmax_q16;
    int32_t v = (c->prof_v_q16 ^ s) - s;             /* speed toward the target (|v| < 2^31) */
    int32_t w;
    if (TL_LIKELY(c->prof_st == TL_PROF_ACCEL)) {
        /* u = min(v + a, vmax) and what it takes from E: u + v speeding up by a or reaching vmax,
         * vmax cruising (at or above vmax); 32 bits: u + v < 2^31 (v < vmax <= 2^30 when counted) */
        int32_t u = v + a;
        u = u > vmax ? vmax : u;
        int32_t step = u + (v & -(int32_t)(v < vmax));
        /* the common case in 32 bits: E's low part covers the step, v >= 0; one branch (moving
         * away, the low part spent, braking: below) */
        int32_t e = (int32_t)((uint32_t)c->prof_e32 - (uint32_t)step);
        if (TL_LIKELY((e | v) >= 0)) {
            c->prof_e32 = e;
            profile_out(c, u, s);
            return;
        }
        int32_t b = v & ~(v >> 31);                  /* brake from b = max(v, 0): R = E = d - S(b) < 2b + a */
        uint32_t r = (uint32_t)c->prof_e32;
        if (TL_UNLIKELY((c->prof_eres != 0) | (v < 0))) {
            step = v < 0 ? u : step;                 /* moving away: S(v) counts as 0 (E = d) */
            /* moving away, or the low part spent with more in reserve: in 64 bits */
            int64_t en = profile_e(c) - step;
            if (u <= 0 || !neg64(en)) {              /* braking from u still stops short of the target */
                int32_t lo = (uint64_t)en >> 31 ? 0x7FFFFFFF : (int32_t)en;   /* en >= 0 here */
                c->prof_e32 = lo;
                c->prof_eres = en - lo;
                profile_out(c, u, s);
                return;
            }
            r = (uint32_t)c->prof_eres + (uint32_t)c->prof_e32;   /* R < 2^31: the low words give it */
        }
        if (TL_LIKELY(v >= vmax)) {                  /* braking from vmax: R = d - S(vmax), which E may */
            b = vmax;                                /* have underestimated on reaching vmax (by <= v); */
            uint32_t dl = (uint32_t)c->target_q16 - (uint32_t)c->sp_q16;   /* R < 2^31: low words */
            r = ((dl ^ (uint32_t)s) - (uint32_t)s) - (uint32_t)c->d.s_vmax;
        }
        uint32_t p2 = r >> 1;
        p2 = p2 < (uint32_t)b ? p2 : (uint32_t)b;
        c->prof_p1 = r - p2;
        c->prof_p2 = p2;
        c->prof_b = (uint32_t)b;
        c->prof_st = TL_PROF_BRAKE;
    } else if (c->prof_st == TL_PROF_OVERRUN) {
        w = v - a;                                   /* v > a: E = d - S(v) is the same after braking by a */
        profile_out(c, w, s);
        if (w <= a) {                                /* the last speed past the target: turn toward it */
            c->prof_s = ~s;
            profile_set_e(c, -profile_e(c));         /* S(w) = 0: E is d */
            c->prof_st = TL_PROF_ACCEL;
        }
        return;
    }
    if (profile_brake(c, a, &w)) {                   /* nothing left: this sample lands */
        c->sp_q16 = c->target_q16;
        profile_rest(c);
        return;
    }
    profile_out(c, w, s);
}

/* |d| counts over dt cycles in q8 counts/s, saturated to INT32_MAX (control.h,
 * TL_CTL_SPEED_TAB): v = (floor(N / 2^k) / dt) << k with N = |d| clk 2^8 and k the
 * smallest shift that brings N below 2^32 - one divide; below the exact floor(N / dt)
 * by less than 2^(k+1) q8 (docs/firmware.md, "Control"). */
static inline __attribute__((always_inline)) int32_t edge_speed(const tl_ctl_t *c, uint32_t ad, uint32_t dt)
{
    uint32_t m, k;
    if (TL_LIKELY(ad < TL_CTL_SPEED_TAB)) {
        m = tl_ctl_speed_m[ad];
        k = tl_ctl_speed_k[ad];
    } else {
        if (ad > TL_CTL_DCOUNT_MAX)
            ad = TL_CTL_DCOUNT_MAX;
        m = tl_speed_numerator((uint64_t)ad * c->d.clk_q8, &k);
    }
    uint32_t q = m / dt;
    return q > (0x7FFFFFFFu >> k) ? 0x7FFFFFFF : (int32_t)(q << k);
}

static inline __attribute__((always_inline)) void velocity(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos,
                                                            uint32_t edge_time, uint32_t now, uint32_t interval)
{
    if (TL_UNLIKELY(p->vel_mode == 0u)) {
        /* The paper: Euler difference over T_s, low-pass weight 1/2 (torqueloop/sim/model_loop.py),
         * with 2^8 1e6 / T_s rounded once per configuration (exact for T_s dividing 2^14 5^6 us). */
        int64_t euler = (int64_t)count_diff(pos, c->pos_prev) * c->d.euler_k;
        c->vel_q8 = (int32_t)clamp64((euler + c->vel_q8) / 2, -0x7FFFFFFF, 0x7FFFFFFF);
    } else if (pos != c->pos_ref) {
        /* Moving since the last sample: distance over the time between the decoder's edge
         * timestamps - the exact average speed, free of sampling quantisation.  First counts
         * after a silent sample: the old reference edge dates from before the standstill,
         * so take one count over the decoder's last edge interval instead. */
        int32_t d = count_diff(pos, c->pos_ref);
        uint32_t dt = edge_time - c->t_ref;
        if (TL_UNLIKELY(!c->moved_last)) {
            d = d > 0 ? 1 : -1;
            dt = interval;
        }
        dt |= (uint32_t)(dt == 0u);                  /* 0 as 1; no branch */
        int32_t sd = d >> 31;                        /* the direction as a sign mask: no branch */
        int32_t v = edge_speed(c, (uint32_t)(d ^ sd) - (uint32_t)sd, dt);
        c->vel_q8 = (v ^ sd) - sd;
        c->pos_ref = pos;
        c->t_ref = edge_time;
        c->moved_last = true;
    } else {
        c->moved_last = false;
        /* No count this sample: the speed cannot exceed one count over the time since the
         * last edge, so the estimate decays as 1/t to zero when the axis stops. */
        uint32_t dt = now - c->t_ref;
        if (TL_UNLIKELY(dt > 0x7FFFFFFFu))
            c->t_ref = now - 0x7FFFFFFFu;   /* keep the reference inside the 32-bit window */
        /* |v| clamped to the bound floor(m / dt) 2^k (m, k: one count): one divide and no branch
         * (the bound clamps every period while the estimate decays, the dearest standstill case) */
        int32_t v = c->vel_q8, sv = v >> 31;
        uint32_t av = (uint32_t)(v ^ sv) - (uint32_t)sv;
        uint32_t q = c->d.bound_m / (dt | (uint32_t)(dt == 0u)), k = c->d.bound_k;   /* dt 0 as 1: no clamp either way */
        uint32_t bound = q > (0x7FFFFFFFu >> k) ? 0x7FFFFFFFu : q << k;   /* edge_speed(c, 1, dt) */
        uint32_t over = 0u - (uint32_t)(av > bound);
        av = (av & ~over) | (bound & over);
        c->vel_q8 = (int32_t)(av ^ (uint32_t)sv) - sv;
    }
    c->pos_prev = pos;
}

/* The 64-bit product of two 32-bit numbers: mul and mulh on RV32IM (GCC 12
 * otherwise sign-extends an operand it cannot see is 32-bit and multiplies
 * 64 by 32 bits, four multiplies). */
static inline int64_t mul32(int32_t a, int32_t b)
{
#if defined(__riscv) && __riscv_xlen == 32
    int32_t hi;
    __asm__("mulh %0, %1, %2" : "=r"(hi) : "r"(a), "r"(b));
    return (int64_t)(((uint64_t)(uint32_t)hi << 32) | ((uint32_t)a * (uint32_t)b));
#else
    return (int64_t)a * (int64_t)b;
#endif
}

/* x * y for 0 <= x < 2^63 whose product with y fits 64 bits: three multiplies on RV32IM
 * (mulhsu takes y's sign; GCC 12 sign-extends y to 64 bits and spends a fourth). */
static inline int64_t mul64u32s(int64_t x, int32_t y)
{
#if defined(__riscv) && __riscv_xlen == 32
    uint32_t lo = (uint32_t)x, hi;
    __asm__("mulhsu %0, %1, %2" : "=r"(hi) : "r"(y), "r"(lo));
    hi += (uint32_t)(x >> 32) * (uint32_t)y;
    return (int64_t)(((uint64_t)hi << 32) | (lo * (uint32_t)y));
#else
    return x * y;
#endif
}

/* v saturated to +-0x7FFFFFFF (the law's error range). */
static inline int32_t sat31(int64_t v) { return v > 0x7FFFFFFF ? 0x7FFFFFFF : (v < -0x7FFFFFFF ? -0x7FFFFFFF : (int32_t)v); }

/* Friction compensation beyond eq. (1), added to the law's P and D part in q16 PWM steps:
 * velocity feed-forward Kvff v_sp (v_sp the trapezoid profile's speed, q8 counts/s: counts
 * per sample q16 times euler_k = 2^8 1e6 / T, saturated to 31 bits), acceleration
 * feed-forward Kaff a_sp (a_sp the profile speed's change over the sample, q8 counts/s^2:
 * counts per sample^2 q16 times euler_k twice, each product saturated to 31 bits), then the dead zone
 * beyond PW0 per direction: FC_POS steps added to a positive command, FC_NEG to the size of a
 * negative one (the sign of pd + i before rounding), then the dither: +DITHER_AMP steps for
 * DITHER_HALF samples, -DITHER_AMP for the next DITHER_HALF, while the error e (after the
 * dead band) is nonzero and outside the hunting guard's zone; inside, the dither is off and
 * its phase held (docs/firmware.md, "Control").  Zero parameters add nothing. */
static inline __attribute__((always_inline)) void friction_terms(tl_ctl_t *c, const tl_ctl_params_t *p,
                                                                  int64_t *pd_q16, int32_t i_q16, int32_t e)
{
    if (p->kvff_q16 != 0 && c->prof_v_q16 != 0) {
        int32_t v_q8 = sat31(((int64_t)c->prof_v_q16 * c->d.euler_k) >> 16);
        *pd_q16 += mul32(p->kvff_q16, v_q8) >> 8;
    }
    if (p->kaff_q16 != 0 && c->prof_a_q16 != 0) {
        int32_t dv_q8 = sat31(mul32(c->prof_a_q16, c->d.euler_k) >> 16);
        int32_t a_q8 = sat31(mul32(dv_q8, c->d.euler_k) >> 8);
        *pd_q16 += mul32(p->kaff_q16, a_q8) >> 8;
    }
    if ((p->fc_pos | p->fc_neg) != 0) {
        int64_t u = *pd_q16 + i_q16;
        if (u > 0)
            *pd_q16 += (int64_t)p->fc_pos << 16;
        else if (u < 0)
            *pd_q16 -= (int64_t)p->fc_neg << 16;
    }
    if (p->dither_amp != 0 && e != 0 && !(p->izone_q16 != 0 && (e < 0 ? -e : e) <= p->izone_q16)) {
        uint32_t n = c->dither_n, h = (uint32_t)p->dither_half;
        int64_t d = (int64_t)p->dither_amp << 16;
        *pd_q16 += n < h ? d : -d;
        c->dither_n = ++n >= 2u * h ? 0u : n;
    }
}

/* The law's output (eq. 19/25): u = (pd + i + 2^15) >> 16 rounded and saturated to +-limit,
 * the saturation's sign kept for the anti-windup.  Bounds within +-2^26 (CMD_LIMIT <= 1023),
 * |i| < 2^27: with |pd| < 2^30 the sum fits 32 bits; beyond, pd's sign decides. */
static inline __attribute__((always_inline)) int32_t law_output(tl_ctl_t *c, int64_t pd_q16, int32_t i_q16, int32_t limit)
{
    int32_t pd = (int32_t)pd_q16;
    int32_t cmd;
    if (TL_LIKELY((int32_t)(pd_q16 >> 32) == (pd >> 31) && (uint32_t)pd + 0x40000000u < 0x80000000u)) {
        int32_t t = pd + i_q16 + 32768, lo = (int32_t)c->d.sat_lo_q16;
        if (TL_LIKELY((uint32_t)t - (uint32_t)lo < (uint32_t)c->d.sat_hi_q16 - (uint32_t)lo)) {   /* lo <= t < hi */
            cmd = t >> 16;
            c->sat_sign = 0;
        } else if (t >= lo) {
            cmd = limit;
            c->sat_sign = 1;
        } else {
            cmd = -limit;
            c->sat_sign = -1;
        }
    } else if (pd_q16 > 0) {
        cmd = limit;
        c->sat_sign = 1;
    } else {
        cmd = -limit;
        c->sat_sign = -1;
    }
    return cmd;
}

static inline __attribute__((always_inline)) int32_t law(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, bool run_law)
{
    /* The law's kind and the operands of its first products read first: the instructions that use
     * them would otherwise wait for their loads (2 cycles each on tl_cpu_pipe). */
    uint32_t kind = p->law;
    int32_t kd = p->kd_q16, vel = c->vel_q8, ki_e_max = c->d.ki_e_max;
    int64_t ki_dt = c->d.ki_dt_q32;
    /* The error, q16 counts: 32 bits within +-32767 counts (the usual case), saturated beyond. */
    /* sp - pos 2^16 by words: pos 2^16 is (pos >> 16 : pos << 16), no 64-bit shift */
    uint32_t slo = (uint32_t)c->sp_q16, plo = (uint32_t)pos << 16;
    int32_t ehi = (int32_t)((uint64_t)c->sp_q16 >> 32) - (pos >> 16) - (int32_t)(slo < plo);
    int32_t e = (int32_t)(slo - plo);   /* fits: the high word is e's sign and e is not INT32_MIN, one branch */
    bool fits = (((uint32_t)ehi ^ (uint32_t)(e >> 31)) | (uint32_t)(e == INT32_MIN)) == 0u;
    int64_t e_q16 = (int64_t)(((uint64_t)(uint32_t)ehi << 32) | (uint32_t)e);
    if (TL_LIKELY(fits)) {
        c->err_counts = (e >> 16) + ((e >> 15) & 1);   /* (e + 2^15) >> 16 without overflow */
    } else {
        c->err_counts = sat31((e_q16 + 32768) >> 16);
        e = e_q16 < 0 ? -0x7FFFFFFF : 0x7FFFFFFF;
    }
    if (TL_UNLIKELY(!run_law || kind == TL_LAW_OFF)) {
        c->integ_q32 = 0;
        c->dither_n = 0;
        return 0;
    }
    uint32_t ae = (uint32_t)(e ^ (e >> 31)) - (uint32_t)(e >> 31);   /* |e| (e > INT32_MIN here) */
    e &= (int32_t)((uint32_t)(fits & (ae <= (uint32_t)p->deadband_q16)) - 1u);   /* 0 inside the dead band; no branch */
    int32_t limit = p->cmd_limit;
    /* eq. (20): P;  eq. (21): + Kd * (0 - v);  eq. (22): + Ki * integral(e) */
    int64_t pd_q16 = mul32(p->kp_q16, e) >> 16;
    if (kind >= TL_LAW_PD)
        pd_q16 -= mul32(kd, vel) >> 8;
    int32_t i_q16 = 0;
    if (TL_LIKELY(kind == TL_LAW_PID)) {
        int32_t e_sign = (e > 0) - (e < 0);
        bool frozen = (c->sat_sign != 0) & (e_sign == c->sat_sign);   /* & not &&: no branch */
        if (TL_UNLIKELY(c->d.friction) && p->izone_q16 != 0 && (e < 0 ? -e : e) <= p->izone_q16)
            frozen = true;   /* the hunting guard */
        if (TL_LIKELY(!frozen)) {
            int32_t ek = e;
            if (TL_UNLIKELY(e > ki_e_max))
                ek = ki_e_max;
            else if (TL_UNLIKELY(e < -ki_e_max))
                ek = -ki_e_max;
            int64_t i = c->integ_q32 + (mul64u32s(ki_dt, ek) >> 16);
            /* clamp to +-cmd_limit q32, whose low word is zero: compare high words */
            int32_t ih = (int32_t)(i >> 32);
            if (TL_UNLIKELY(ih >= limit && (ih > limit || (uint32_t)i != 0u)))
                i = c->d.lim_q32;
            else if (TL_UNLIKELY(ih < -limit))
                i = -c->d.lim_q32;
            c->integ_q32 = i;
        }
        /* |integ| <= CMD_LIMIT 2^32 <= 1023 2^32 (every update is clamped): 27 bits in q16 */
        i_q16 = (int32_t)(c->integ_q32 >> 16);
    } else {
        c->integ_q32 = 0;
    }
    if (TL_UNLIKELY(c->d.friction))
        friction_terms(c, p, &pd_q16, i_q16, e);
    return law_output(c, pd_q16, i_q16, limit);
}

static inline __attribute__((always_inline)) int32_t tl_ctl_step_inline(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos,
                                                                       uint32_t edge_time, uint32_t now, uint32_t interval,
                                                                       bool run_law)
{
    velocity(c, p, pos, edge_time, now, interval);
    if (TL_LIKELY(c->moving))
        profile(c);
    return law(c, p, pos, run_law);
}

#endif
