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

#define INT64_MAXV ((int64_t)0x7FFFFFFFFFFFFFFFLL)

static int64_t clamp64(int64_t v, int64_t lo, int64_t hi) { return v < lo ? lo : (v > hi ? hi : v); }
static int64_t abs64(int64_t v) { return v < 0 ? -v : v; }
/* Counts between two decoder readings: the 32-bit counter wraps, so the
 * difference is taken modulo 2^32 (a signed subtraction would overflow). */
static int32_t count_diff(int32_t a, int32_t b) { return (int32_t)((uint32_t)a - (uint32_t)b); }

void tl_ctl_reset(tl_ctl_t *c, int32_t pos, uint32_t t_now)
{
    c->sp_q16 = (int64_t)pos * 65536;
    c->target_q16 = c->sp_q16;
    c->prof_v_q16 = 0;
    c->moving = false;
    c->integ_q32 = 0;
    c->saturated = false;
    c->sat_sign = 0;
    c->vel_q8 = 0;
    c->pos_prev = pos;
    c->pos_ref = pos;
    c->t_ref = t_now;
    c->moved_last = false;
    c->err_counts = 0;
    c->cmd = 0;
}

void tl_ctl_derive(tl_ctl_t *c, const tl_ctl_params_t *p, uint32_t period_us, uint32_t clk_hz)
{
    /* x * 2^16 / 1e6 = x * 1024 / 15625 and x * 2^16 / 1e12 = x * 16 / 5^12: exact, no overflow. */
    c->period_us = period_us;
    c->clk_hz = clk_hz;
    c->ki_dt_q32 = (int64_t)p->ki_q16 * (int64_t)period_us * 1024 / 15625;
    c->e_max_for_ki = c->ki_dt_q32 > 0 ? INT64_MAXV / 4 / c->ki_dt_q32 : INT64_MAXV;
    c->vmax_q16 = (int64_t)p->vmax_cps * (int64_t)period_us * 1024 / 15625;
    if (c->vmax_q16 < 1)
        c->vmax_q16 = 1;
    c->amax_q16 = (int64_t)p->amax_cps2 * (int64_t)period_us * (int64_t)period_us * 16 / 244140625;
    if (c->amax_q16 < 1)
        c->amax_q16 = 1;
}

void tl_ctl_move(tl_ctl_t *c, int32_t target, bool trapezoid)
{
    c->target_q16 = (int64_t)target * 65536;
    if (trapezoid) {
        c->moving = true;
    } else {
        c->sp_q16 = c->target_q16;   /* the paper's step experiment */
        c->prof_v_q16 = 0;
        c->moving = false;
    }
}

void tl_ctl_hold(tl_ctl_t *c, int32_t pos)
{
    c->sp_q16 = (int64_t)pos * 65536;
    c->target_q16 = c->sp_q16;
    c->prof_v_q16 = 0;
    c->moving = false;
}

static uint64_t isqrt64(uint64_t x)
{
    uint64_t r = 0, bit = (uint64_t)1 << 62;
    while (bit > x)
        bit >>= 2;
    while (bit) {
        if (x >= r + bit) {
            x -= r + bit;
            r = (r >> 1) + bit;
        } else {
            r >>= 1;
        }
        bit >>= 2;
    }
    return r;
}

/* Fastest speed v (counts per sample, q16) from which braking by a per sample
 * stops exactly after d: v + (v - a) + ... + (v - n a) = d with n = floor(v / a),
 * i.e. n = largest with a n (n + 1) / 2 <= d, v = (d + a n (n + 1) / 2) / (n + 1). */
static int64_t v_allow(uint64_t d, int64_t a)
{
    uint64_t ua = (uint64_t)a;
    uint64_t n = (isqrt64(8u * (d / ua) + 1u) - 1u) / 2u;
    while (n > 0u && ua * n * (n + 1u) / 2u > d)
        n--;
    while (ua * (n + 1u) * (n + 2u) / 2u <= d)
        n++;
    return (int64_t)((d + ua * n * (n + 1u) / 2u) / (n + 1u));
}

/* Trapezoidal profile: each sample the speed toward the target rises by at
 * most a, never exceeds vmax, and never exceeds the speed from which braking
 * by a per sample lands exactly on the target; the last step lands on it. */
static void profile(tl_ctl_t *c)
{
    if (!c->moving)
        return;
    int64_t d = c->target_q16 - c->sp_q16;
    int64_t dir = d >= 0 ? 1 : -1;
    uint64_t ad = (uint64_t)abs64(d);
    int64_t vs = c->prof_v_q16 * dir + c->amax_q16;   /* speed toward the target, accelerated */
    int64_t va = v_allow(ad, c->amax_q16);
    if (vs > c->vmax_q16)
        vs = c->vmax_q16;
    if (vs > va)
        vs = va;
    if (vs >= 0 && (uint64_t)vs >= ad) {
        c->sp_q16 = c->target_q16;
        c->prof_v_q16 = 0;
        c->moving = false;
        return;
    }
    c->prof_v_q16 = vs * dir;
    c->sp_q16 += c->prof_v_q16;
}

static void velocity(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, uint32_t edge_time, uint32_t now,
                     uint32_t interval)
{
    if (p->vel_mode == 0u) {
        /* The paper: Euler difference over T_s, low-pass weight 1/2 (torqueloop/sim/model_loop.py). */
        int64_t euler = (int64_t)count_diff(pos, c->pos_prev) * 256 * 1000000 / (int64_t)c->period_us;
        c->vel_q8 = (int32_t)clamp64((euler + c->vel_q8) / 2, -0x7FFFFFFF, 0x7FFFFFFF);
    } else if (pos != c->pos_ref) {
        /* Moving since the last sample: distance over the time between the decoder's edge
         * timestamps - the exact average speed, free of sampling quantisation.  First counts
         * after a silent sample: the old reference edge dates from before the standstill,
         * so take one count over the decoder's last edge interval instead. */
        int64_t d = count_diff(pos, c->pos_ref);
        uint32_t dt = edge_time - c->t_ref;
        if (!c->moved_last) {
            d = d > 0 ? 1 : -1;
            dt = interval;
        }
        if (dt == 0u)
            dt = 1u;
        int64_t v = d * 256 * (int64_t)c->clk_hz / (int64_t)dt;
        c->vel_q8 = (int32_t)clamp64(v, -0x7FFFFFFF, 0x7FFFFFFF);
        c->pos_ref = pos;
        c->t_ref = edge_time;
        c->moved_last = true;
    } else {
        c->moved_last = false;
        /* No count this sample: the speed cannot exceed one count over the time since the
         * last edge, so the estimate decays as 1/t to zero when the axis stops. */
        uint32_t dt = now - c->t_ref;
        if (dt > 0x7FFFFFFFu)
            c->t_ref = now - 0x7FFFFFFFu;   /* keep the reference inside the 32-bit window */
        int64_t bound = dt ? 256 * (int64_t)c->clk_hz / (int64_t)dt : 0x7FFFFFFF;
        int64_t v = c->vel_q8;
        if (abs64(v) > bound)
            c->vel_q8 = (int32_t)(v > 0 ? bound : -bound);
    }
    c->pos_prev = pos;
}

int32_t tl_ctl_step(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, uint32_t edge_time, uint32_t now,
                    uint32_t interval, bool run_law)
{
    velocity(c, p, pos, edge_time, now, interval);
    profile(c);
    int64_t e_q16 = c->sp_q16 - (int64_t)pos * 65536;
    c->err_counts = (int32_t)clamp64((e_q16 + 32768) >> 16, -0x7FFFFFFF, 0x7FFFFFFF);
    if (!run_law || p->law == TL_LAW_OFF) {
        c->integ_q32 = 0;
        c->cmd = 0;
        return 0;
    }
    if (abs64(e_q16) <= p->deadband_q16)
        e_q16 = 0;
    e_q16 = clamp64(e_q16, -0x7FFFFFFF, 0x7FFFFFFF);
    int64_t limit = p->cmd_limit;
    /* eq. (20): P;  eq. (21): + Kd * (0 - v);  eq. (22): + Ki * integral(e) */
    int64_t u_q16 = ((int64_t)p->kp_q16 * e_q16) >> 16;
    if (p->law >= TL_LAW_PD)
        u_q16 -= ((int64_t)p->kd_q16 * c->vel_q8) >> 8;
    if (p->law == TL_LAW_PID) {
        int32_t e_sign = e_q16 > 0 ? 1 : (e_q16 < 0 ? -1 : 0);
        if (!(c->saturated && e_sign == c->sat_sign)) {
            int64_t e = clamp64(e_q16, -c->e_max_for_ki, c->e_max_for_ki);
            c->integ_q32 = clamp64(c->integ_q32 + ((c->ki_dt_q32 * e) >> 16),
                                   -(limit << 32), limit << 32);
        }
        u_q16 += c->integ_q32 >> 16;
    } else {
        c->integ_q32 = 0;
    }
    int64_t u = (u_q16 + 32768) >> 16;   /* round to the nearest PWM step */
    /* eq. (19)/(25): saturate to the command range */
    c->saturated = u > limit || u < -limit;
    c->sat_sign = u > limit ? 1 : (u < -limit ? -1 : 0);
    c->cmd = (int32_t)clamp64(u, -limit, limit);
    return c->cmd;
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
