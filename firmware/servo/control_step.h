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

/* Trapezoidal profile: each sample the speed toward the target rises by at
 * most a, never exceeds vmax, and never exceeds v_allow(d), the speed from
 * which braking by a per sample lands exactly on the target after d; the last
 * step lands on it (never beyond).
 *
 * Braking by a from v covers D(v) = v + (v - a) + ... + (v - m a) = (m + 1)(2v - a m) / 2
 * with m = floor(v / a), increasing in v, and D(v_allow(d)) <= d < D(v_allow(d) + 1), so
 * "v <= v_allow(d)" is "D(v) <= d": no square root.  m is carried from sample to sample
 * (v + a has m + 1, vmax has m_vmax, v_allow has n), so no sample divides by a.  When
 * braking, v_allow(d) = floor((d + a n (n + 1) / 2) / (n + 1)) with n = m(v_allow);
 * because D(v - a) = D(v) - v, the last speed v was on or inside the braking curve and
 * v_allow lies in [v - a, v + a): n is m(v - a) or one or two more, found by walking D up
 * from D(v - a) segment by segment, and the quotient is a remainder over n + 1 that fits
 * 32 bits.  D(|v|) itself is carried from sample to sample: no sample multiplies for it while
 * accelerating or cruising.  If a new target or a lower vmax
 * leaves the axis unable to stop in time (D(v - a) > d), it brakes by a and comes back. */
static inline uint64_t stop_distance(uint32_t v, uint32_t m, uint32_t a)
{
    return ((uint64_t)(m + 1u) * (uint64_t)(2u * v - a * m)) >> 1;   /* 2v - a m = v + (v mod a) < 2^31 */
}

/* floor(x / k), k >= 1, and the remainder in *rem: below TL_CTL_SPEED_TAB through the
 * reciprocal table (a multiply, a check and at most one correction: floor(x R / 2^32) with
 * R = floor((2^32 - 1) / k) is the quotient or one less), the hardware divide (35 cycles) beyond. */
static inline uint32_t div_small(uint32_t x, uint32_t k, uint32_t *rem)
{
    uint32_t q = TL_LIKELY(k < TL_CTL_SPEED_TAB) ? (uint32_t)(((uint64_t)x * tl_ctl_recip[k]) >> 32) : x / k;
    uint32_t r = x - opaque(q) * k;
    uint32_t over = (uint32_t)(r >= k);              /* the correction as a mask: no branch */
    *rem = r - (k & (0u - over));
    return q + over;
}

/* The profile at rest on the set-point (no speed, no stopping distance, no acceleration). */
static inline __attribute__((always_inline)) void profile_rest(tl_ctl_t *c)
{
    c->prof_v_q16 = 0;
    c->prof_m = 0;
    c->prof_dv = 0;
    c->prof_a_q16 = 0;
    c->moving = false;
}

static inline __attribute__((always_inline)) void profile(tl_ctl_t *c)
{
    int64_t d = c->target_q16 - c->sp_q16;
    int32_t s = (int32_t)(d >> 63);                  /* toward the target: 0 up, -1 down */
    int64_t ad = (d ^ s) - s;                        /* |d| < 2^48: positions are 32-bit counts in q16 */
    uint32_t a = (uint32_t)c->d.amax_q16;
    int32_t v = (c->prof_v_q16 ^ s) - s;             /* speed toward the target (|v| < 2^31), accelerated: */
    int32_t vs = v + (int32_t)a;
    uint32_t m = v >= 0 ? c->prof_m + 1u : (c->prof_m ? c->prof_m - 1u : 0u);
    /* D(|v|) is carried from sample to sample (prof_dv), and both tests below follow from it:
     * D(v + a) = D(v) + v + a and D(v - a) = D(v) - v (the sum's first or last term). */
    uint64_t dv = c->prof_dv;
    uint64_t dvs = dv + (uint32_t)vs, dn;            /* dn: D(|vs|), for the next sample */
    if (vs > c->d.vmax_q16) {
        vs = c->d.vmax_q16;
        m = c->d.m_vmax;
        dvs = vs == v ? dv : stop_distance((uint32_t)vs, m, a);   /* cruising: D(vmax) is D(v) */
        dn = dvs;
    } else if (TL_UNLIKELY(v < 0)) {
        dvs = vs > 0 ? stop_distance((uint32_t)vs, m, a) : 0u;
        dn = vs > 0 ? dvs : dv - (0u - (uint32_t)v);  /* D(|v| - a) = D(|v|) - |v| */
    } else {
        dn = dvs;
    }
    /* Distances and stopping distances are below 2^62 (D(v) < 2^31 (m + 1)): each 64-bit test is
     * the sign of a difference, one subtraction and one branch. */
    if (neg64(ad - (int64_t)dvs)) {                  /* D(vs) > d; D is 0 for vs <= 0 */
        uint32_t lo = v > (int32_t)a ? (uint32_t)v - a : 0u;   /* v_allow(d) >= lo when on the curve */
        uint32_t mlo = v > (int32_t)a ? c->prof_m - 1u : 0u;
        if (lo > 0u && neg64(ad - (int64_t)(dv - (uint32_t)v))) {
            vs = (int32_t)lo;                        /* cannot stop in time: brake by a */
            m = mlo;
            dn = dv - (uint32_t)v;
        } else {
            /* v_allow in [lo, vs): D grows by m + 1 per q16 count of speed inside a segment
             * [a m, a (m + 1)) of constant m, from D(lo) in lo's segment mlo, and vs <= a (mlo + 3):
             * at most three segments, then one quotient.  r = d - D(lo) < D(vs) - D(lo) <= 2v + a
             * < 2^32 (speeds <= 2^30, a < 2^29): 32-bit, so the low words give it exactly. */
            uint32_t r = (uint32_t)ad - (lo ? (uint32_t)dv - (uint32_t)v : 0u);
            uint32_t n = mlo, b = a * (n + 1u), base = lo;   /* b: the segment's end (< 2^31) */
            uint32_t span = (n + 1u) * (b - lo);             /* D over the rest of lo's segment */
            if (r >= span) {
                r -= span;
                n++;
                base = b;
                span = (n + 1u) * a;                         /* a (mlo + 2) < 2^32 */
                if (r >= span) {
                    r -= span;
                    n++;
                    base += a;
                }
            }
            uint32_t rem;
            vs = (int32_t)(base + div_small(r, n + 1u, &rem));
            m = n;
            dn = (uint64_t)ad - rem;                 /* D(base) + (n + 1) q = d - r + (n + 1) q */
        }
    }
    if (!neg64((int64_t)vs - ad)) {                 /* vs >= d: lands (never when vs < 0) */
        c->sp_q16 = c->target_q16;
        profile_rest(c);
        return;
    }
    vs = (vs ^ s) - s;
    c->prof_a_q16 = vs - c->prof_v_q16;   /* at most a, or a drop to a lower vmax: fits 31 bits */
    c->prof_v_q16 = vs;
    c->prof_m = m;
    c->prof_dv = dn;
    c->sp_q16 += c->prof_v_q16;
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

static inline __attribute__((always_inline)) int32_t law(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, bool run_law)
{
    /* The error, q16 counts: 32 bits within +-32767 counts (the usual case), saturated beyond. */
    int64_t e_q16 = c->sp_q16 - (int64_t)pos * 65536;
    int32_t e = (int32_t)e_q16;   /* fits: the high word is e's sign and e is not INT32_MIN, one branch */
    bool fits = (((uint32_t)(e_q16 >> 32) ^ (uint32_t)(e >> 31)) | (uint32_t)(e == INT32_MIN)) == 0u;
    if (TL_LIKELY(fits)) {
        c->err_counts = (e >> 16) + ((e >> 15) & 1);   /* (e + 2^15) >> 16 without overflow */
    } else {
        c->err_counts = sat31((e_q16 + 32768) >> 16);
        e = e_q16 < 0 ? -0x7FFFFFFF : 0x7FFFFFFF;
    }
    if (TL_UNLIKELY(!run_law || p->law == TL_LAW_OFF)) {
        c->integ_q32 = 0;
        c->dither_n = 0;
        c->cmd = 0;
        return 0;
    }
    uint32_t ae = (uint32_t)(e ^ (e >> 31)) - (uint32_t)(e >> 31);   /* |e| (e > INT32_MIN here) */
    e &= (int32_t)((uint32_t)(fits & (ae <= (uint32_t)p->deadband_q16)) - 1u);   /* 0 inside the dead band; no branch */
    int32_t limit = p->cmd_limit;
    /* eq. (20): P;  eq. (21): + Kd * (0 - v);  eq. (22): + Ki * integral(e) */
    int64_t pd_q16 = mul32(p->kp_q16, e) >> 16;
    if (p->law >= TL_LAW_PD)
        pd_q16 -= mul32(p->kd_q16, c->vel_q8) >> 8;
    int32_t i_q16 = 0;
    if (TL_LIKELY(p->law == TL_LAW_PID)) {
        int32_t e_sign = (e > 0) - (e < 0);
        bool frozen = (c->sat_sign != 0) & (e_sign == c->sat_sign);   /* & not &&: no branch */
        if (TL_UNLIKELY(c->d.friction) && p->izone_q16 != 0 && (e < 0 ? -e : e) <= p->izone_q16)
            frozen = true;   /* the hunting guard */
        if (TL_LIKELY(!frozen)) {
            int32_t ek = e;
            if (TL_UNLIKELY(e > c->d.ki_e_max))
                ek = c->d.ki_e_max;
            else if (TL_UNLIKELY(e < -c->d.ki_e_max))
                ek = -c->d.ki_e_max;
            int64_t i = c->integ_q32 + (mul64u32s(c->d.ki_dt_q32, ek) >> 16);
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
    /* round and saturate (eq. 19/25): u = (pd + i + 2^15) >> 16.  Bounds within +-2^26 (CMD_LIMIT
     * <= 1023), |i| < 2^27: with |pd| < 2^30 the sum fits 32 bits; beyond, pd's sign decides. */
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
    c->saturated = c->sat_sign != 0;
    c->cmd = cmd;
    return cmd;
}

static inline __attribute__((always_inline)) int32_t tl_ctl_step_inline(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos,
                                                                       uint32_t edge_time, uint32_t now, uint32_t interval,
                                                                       bool run_law)
{
    velocity(c, p, pos, edge_time, now, interval);
    if (c->moving)
        profile(c);
    return law(c, p, pos, run_law);
}

#endif
