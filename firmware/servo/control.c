/* SPDX-License-Identifier: MIT */
/* Position control of one axis (control.h).  Why the choices:
 *  - derivative of the measured velocity, not of the error (eq. 21-22 with
 *    e' = x_d' - x' and x_d' = 0 between set-point changes): a set-point step
 *    does not kick the output;
 *  - the integrator accumulates Ki * e * T_s (not e alone), so changing Ki at
 *    run time does not make the output jump, and it holds while the output is
 *    saturated in the direction the error pushes (anti-windup);
 *  - the error inside the deadband (half a count by default) counts as zero,
 *    so the PI does not hunt between two encoder counts. */
#include "control.h"
#include "control_step.h"

static uint32_t clz32(uint32_t x)
{
    uint32_t n = 0;
    if (x <= 0x0000FFFFu) { n += 16u; x <<= 16; }
    if (x <= 0x00FFFFFFu) { n += 8u; x <<= 8; }
    if (x <= 0x0FFFFFFFu) { n += 4u; x <<= 4; }
    if (x <= 0x3FFFFFFFu) { n += 2u; x <<= 2; }
    if (x <= 0x7FFFFFFFu) { n += 1u; }
    return n;
}

/* Long division in base 2^16 of a normalised divisor (Knuth's algorithm D,
 * two quotient digits), each digit from one 32-bit divide and at most two
 * corrections: the per-sample quotients without libgcc's 64-bit division. */
uint32_t tl_div64_32(uint64_t n, uint32_t d)
{
    uint32_t hi = (uint32_t)(n >> 32), lo = (uint32_t)n;
    if (hi == 0u)
        return lo / d;
    if (hi >= d)
        return UINT32_MAX;
    uint32_t s = clz32(d);
    d <<= s;
    uint32_t dh = d >> 16, dl = d & 0xFFFFu;
    uint32_t u32 = s ? (hi << s) | (lo >> (32u - s)) : hi;
    uint32_t u10 = lo << s;
    uint32_t u1 = u10 >> 16, u0 = u10 & 0xFFFFu;
    uint32_t q1 = u32 / dh, r = u32 - opaque(q1) * dh;
    while (q1 > 0xFFFFu || q1 * dl > ((r << 16) | u1)) {
        q1--;
        r += dh;
        if (r > 0xFFFFu)
            break;
    }
    uint32_t u21 = (u32 << 16) + u1 - q1 * d;   /* modulo 2^32: the true remainder fits */
    uint32_t q0 = u21 / dh;
    r = u21 - opaque(q0) * dh;
    while (q0 > 0xFFFFu || q0 * dl > ((r << 16) | u0)) {
        q0--;
        r += dh;
        if (r > 0xFFFFu)
            break;
    }
    return (q1 << 16) | q0;
}

void tl_ctl_reset(tl_ctl_t *c, int32_t pos, uint32_t t_now)
{
    tl_ctl_hold(c, pos);
    c->integ_q32 = 0;
    c->sat_sign = 0;
    c->vel_q8 = 0;
    c->pos_prev = pos;
    c->pos_ref = pos;
    c->t_ref = t_now;
    c->moved_last = false;
    c->err_counts = 0;
    c->dither_n = 0;   /* enabling resets: the dither starts with a positive half-period */
}

/* floor(x * num / den) for x >= 0 whose quotient by den fits 32 bits, den and
 * (den - 1) * num below 2^32: the conversions per period, without libgcc's 64-bit
 * division, so that a SET_PARAM holds interrupts off for a few hundred cycles. */
TL_FOR_SIZE static int64_t muldiv(uint64_t x, uint32_t num, uint32_t den)
{
    uint32_t q = tl_div64_32(x, den);
    uint32_t r = (uint32_t)(x - (uint64_t)q * den);
    return (int64_t)q * num + (int64_t)(r * num / den);
}

static uint32_t bitlen64(uint64_t x)
{
    uint32_t hi = (uint32_t)(x >> 32);
    return hi ? 64u - clz32(hi) : (x ? 32u - clz32((uint32_t)x) : 0u);
}

uint32_t tl_speed_numerator(uint64_t n, uint32_t *k)
{
    uint32_t b = bitlen64(n);
    *k = b > 32u ? b - 32u : 0u;
    return (uint32_t)(n >> *k);
}

uint32_t tl_ctl_speed_m[TL_CTL_SPEED_TAB];
uint8_t tl_ctl_speed_k[TL_CTL_SPEED_TAB];

/* The speed table for clock clk_hz (the SoC's clock never changes, so a refill
 * writes the values already there and the control iteration may read it meanwhile). */
TL_FOR_SIZE static void speed_table(uint32_t clk_hz)
{
    static uint32_t filled_for;
    if (filled_for == clk_hz && clk_hz)
        return;
    for (uint32_t n = 0; n < TL_CTL_SPEED_TAB; n++) {
        uint32_t k;
        tl_ctl_speed_m[n] = tl_speed_numerator((uint64_t)n * clk_hz * 256u, &k);
        tl_ctl_speed_k[n] = (uint8_t)k;
    }
    filled_for = clk_hz;
}

TL_FOR_SIZE void tl_ctl_derived(tl_ctl_derived_t *d, const tl_ctl_params_t *p, uint32_t period_us, uint32_t clk_hz)
{
    /* x * 2^16 / 1e6 = x * 1024 / 15625 and x * 2^16 / 1e12 = x * 16 / 5^12: exact. */
    d->period_us = period_us;
    d->clk_hz = clk_hz;
    d->ki_dt_q32 = p->ki_q16 > 0 ? muldiv((uint64_t)p->ki_q16 * period_us, 1024u, 15625u) : 0;
    /* |e| up to 2^(61 - bitlen(ki_dt)) keeps ki_dt * e below 2^61; beyond it the
     * increment is 2^12 PWM steps or more, so the integrator saturates either way. */
    uint32_t kb = bitlen64((uint64_t)d->ki_dt_q32);
    d->ki_e_max = kb <= 30u ? 0x7FFFFFFF : (int32_t)(1u << (61u - kb));
    d->lim_q32 = (int64_t)p->cmd_limit << 32;
    d->friction = (p->fc_pos | p->fc_neg | p->izone_q16 | p->kvff_q16 | p->dither_amp | p->kaff_q16) != 0;
    /* u > limit  <=>  u_q16 + 2^15 >= (limit + 1) 2^16;  u < -limit  <=>  u_q16 + 2^15 < -limit 2^16 */
    d->sat_hi_q16 = ((int64_t)p->cmd_limit + 1) * 65536;
    d->sat_lo_q16 = -(int64_t)p->cmd_limit * 65536;
    d->vmax_q16 = (int32_t)clamp64(muldiv((uint64_t)(p->vmax_cps > 0 ? p->vmax_cps : 0) * period_us, 1024u, 15625u),
                                   1, TL_CTL_VMAX_Q16_MAX);
    d->amax_q16 = (int32_t)clamp64(muldiv((uint64_t)(p->amax_cps2 > 0 ? p->amax_cps2 : 0) * period_us * period_us,
                                          16u, 244140625u), 1, TL_CTL_AMAX_Q16_MAX);
    d->s_vmax = stop_sum((uint32_t)d->vmax_q16, (uint32_t)d->amax_q16);
    d->euler_k = (int32_t)((256000000u + period_us / 2u) / period_us);
    d->clk_q8 = (uint64_t)clk_hz * 256u;
    speed_table(clk_hz);
    d->bound_m = tl_ctl_speed_m[1];
    d->bound_k = tl_ctl_speed_k[1];
}

/* The profile's regime and braking surplus from where it is (a new target, vmax or amax; the
 * oracle's _plan): moving away from the target, E = d (it speeds up toward it); otherwise
 * E = d - S(v), and E < 0 means it cannot stop in time (TL_PROF_OVERRUN).  One 32-bit divide. */
static void profile_plan(tl_ctl_t *c)
{
    int64_t d = c->target_q16 - c->sp_q16;
    int32_t s = (int32_t)(d >> 63);
    int32_t v = (c->prof_v_q16 ^ s) - s;
    int64_t e = (d ^ s) - s;
    if (v > 0)
        e -= (int64_t)stop_sum((uint32_t)v, (uint32_t)c->d.amax_q16);
    c->prof_s = s;
    c->prof_st = e < 0 ? TL_PROF_OVERRUN : TL_PROF_ACCEL;
    if (v > c->d.vmax_q16 && e >= 0)   /* above a lowered vmax: E at vmax, where it drops to */
        e = ((d ^ s) - s) - (int64_t)c->d.s_vmax;
    profile_set_e(c, e);
}

void tl_ctl_apply(tl_ctl_t *c, const tl_ctl_derived_t *d)
{
    c->d = *d;
    if (c->moving)
        profile_plan(c);   /* a new vmax or amax mid-move */
}

void tl_ctl_derive(tl_ctl_t *c, const tl_ctl_params_t *p, uint32_t period_us, uint32_t clk_hz)
{
    tl_ctl_derived_t d;
    tl_ctl_derived(&d, p, period_us, clk_hz);
    tl_ctl_apply(c, &d);
}

void tl_ctl_move(tl_ctl_t *c, int32_t target, bool trapezoid)
{
    c->target_q16 = (int64_t)target * 65536;
    if (trapezoid) {
        c->moving = true;
        profile_plan(c);
    } else {
        c->sp_q16 = c->target_q16;   /* the paper's step experiment */
        profile_rest(c);
    }
}

void tl_ctl_hold(tl_ctl_t *c, int32_t pos)
{
    c->sp_q16 = (int64_t)pos * 65536;
    c->target_q16 = c->sp_q16;
    profile_rest(c);
}

/* 2 pi ~ 710 / 113 (error 2.7e-7); the Python side (torqueloop/spec/protocol.py) uses the same. */
int32_t tl_gain_raw_from_phys(int32_t micro, int32_t tau_max_mnm, int32_t counts_per_rev)
{
    if (micro <= 0 || tau_max_mnm <= 0 || counts_per_rev <= 0)
        return 0;
    uint64_t num = (uint64_t)micro * 1023u * 65536u * 710u;
    uint64_t den = (uint64_t)tau_max_mnm * 1000u * (uint64_t)counts_per_rev * 113u;
    uint64_t r = (num + den / 2u) / den;
    return r > 0x7FFFFFFFu ? 0x7FFFFFFF : (int32_t)r;
}

int32_t tl_gain_phys_from_raw(int32_t raw, int32_t tau_max_mnm, int32_t counts_per_rev)
{
    if (raw <= 0 || tau_max_mnm <= 0 || counts_per_rev <= 0)
        return 0;
    uint64_t x = (uint64_t)tau_max_mnm * 1000u * (uint64_t)counts_per_rev * 113u;
    uint64_t den = (uint64_t)1023u * 65536u * 710u;
    if ((uint64_t)raw > UINT64_MAX / x)
        return 100000000;
    uint64_t r = ((uint64_t)raw * x + den / 2u) / den;
    return r > 100000000u ? 100000000 : (int32_t)r;
}

int32_t tl_ctl_step(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, uint32_t edge_time, uint32_t now,
                    uint32_t interval, bool run_law)
{
    return tl_ctl_step_inline(c, p, pos, edge_time, now, interval, run_law);
}
