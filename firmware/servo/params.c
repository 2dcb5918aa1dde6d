/* SPDX-License-Identifier: MIT */
/* Parameters (protocol.toml [[param]], docs/protocol.md "Parameters"): reading
 * and writing them, the rules a value must keep (its range, the bounds between
 * parameters, the tighten-only safety limits) and what they give the control
 * iteration (tl_axis_cfg_t, the period and the link timeout). */
#include "servo_internal.h"

/* Largest physical gain (KP_UNM_RAD, KD_UNMS_RAD, KI_UNM_RADS share the range). */
#define GAIN_PHYS_MAX 100000000

int tl_param_index(uint8_t id) { return TLP_PARAM_INDEX[id]; }
void tl_param_range(uint32_t k, int32_t *lo, int32_t *hi)
{
    *lo = TLP_PARAM_INFO[k].min;
    *hi = TLP_PARAM_INFO[k].max;
}

/* Every parameter's default.  The per-axis ones come from the protocol definition,
 * which takes them from torqueloop/spec/system.toml: the paper's Table 1 P gains,
 * tau_max and carrier of each axis's motor.  (TLP_PARAM_INFO is read here only:
 * each file that reads it holds a copy of its own.) */
TL_FOR_SIZE void tl_params_defaults(tl_servo_t *s)
{
    for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++) {
        s->g[k] = TLP_PARAM_INFO[k].dflt[0];
        for (uint32_t i = 0; i < TL_AXES; i++)
            s->ax[i].p[k] = TLP_PARAM_INFO[k].dflt[i];
    }
#ifdef TL_DEFAULT_PERIOD_US
    s->g[PI(TLP_P_PERIOD_US)] = TL_DEFAULT_PERIOD_US;
#endif
#ifdef TL_DEFAULT_BAUD_DIV
    s->g[PI(TLP_P_BAUD_DIV)] = TL_DEFAULT_BAUD_DIV;
#endif
}

/* From a parameter array; divides, so it runs with interrupts on. */
TL_FOR_SIZE static void axis_cfg(const int32_t *p, uint32_t period_us, uint32_t clk_hz, tl_axis_cfg_t *out)
{
    out->ctl.law = (uint32_t)p[PI(TLP_P_LAW)];
    out->ctl.kp_q16 = p[PI(TLP_P_KP_Q16)];
    out->ctl.kd_q16 = p[PI(TLP_P_KD_Q16)];
    out->ctl.ki_q16 = p[PI(TLP_P_KI_Q16)];
    out->ctl.deadband_q16 = p[PI(TLP_P_DEADBAND_Q16)];
    out->ctl.cmd_limit = p[PI(TLP_P_CMD_LIMIT)];
    out->ctl.vel_mode = (uint32_t)p[PI(TLP_P_VEL_MODE)];
    out->ctl.vmax_cps = p[PI(TLP_P_VMAX)];
    out->ctl.amax_cps2 = p[PI(TLP_P_AMAX)];
    out->ctl.fc_pos = p[PI(TLP_P_FC_POS)];
    out->ctl.fc_neg = p[PI(TLP_P_FC_NEG)];
    out->ctl.izone_q16 = p[PI(TLP_P_IZONE_Q16)];
    out->ctl.kvff_q16 = p[PI(TLP_P_KVFF_Q16)];
    out->ctl.dither_amp = p[PI(TLP_P_DITHER_AMP)];
    out->ctl.dither_half = p[PI(TLP_P_DITHER_HALF)];
    out->ctl.kaff_q16 = p[PI(TLP_P_KAFF_Q16)];
    tl_ctl_derived(&out->d, &out->ctl, period_us, clk_hz);
    uint32_t check_us = period_us * tl_runaway_every(period_us);   /* from one runaway check to the next */
    out->stall_limit_ticks = ((uint32_t)p[PI(TLP_P_STALL_MS)] * 1000u + check_us - 1u) / check_us;
    /* counts/s * us * 2^16 / 1e6 = x * 1024 / 15625, as control.c's vmax; HOME_VEL >= 1, so
     * unsigned (the image then needs no signed 64-bit division from libgcc) */
    out->home_step_q16 = (int64_t)((uint64_t)(uint32_t)p[PI(TLP_P_HOME_VEL)] * period_us * 1024u / 15625u);
    if (out->home_step_q16 < (1 << HOME_SLOW_SHIFT))
        out->home_step_q16 = 1 << HOME_SLOW_SHIFT;
    enc_check_derive(&out->enc, p[PI(TLP_P_ENC_CPS)], p[PI(TLP_P_ENC_TAU_MS)], check_us);
}

/* Hand a configuration to the control iteration: copies, for a critical section. */
static void commit_axis(tl_servo_t *s, uint32_t i, const tl_axis_cfg_t *cfg)
{
    tl_axis_t *a = &s->ax[i];
    a->ctl = cfg->ctl;
    tl_ctl_apply(&a->c, &cfg->d);
    a->stall_limit_ticks = cfg->stall_limit_ticks;
    a->home_step_q16 = cfg->home_step_q16;
    a->enc = cfg->enc;
    hal_pwm_config(i, (uint32_t)pv(a, TLP_P_FDIV), (uint32_t)pv(a, TLP_P_PW0), (uint32_t)pv(a, TLP_P_PWMAX));
    hal_limit_block(i, pv(a, TLP_P_LIMIT_SW) != 0);
    a->limit_mask = pv(a, TLP_P_LIMIT_SW) ? (uint8_t)(TLP_LIMIT_NEG | TLP_LIMIT_POS) : 0u;
}

/* The period in clock cycles and the link timeout in periods, from global parameters g. */
TL_FOR_SIZE static void global_cfg(const int32_t *g, uint32_t clk_hz, uint32_t *period_cycles, uint32_t *link_timeout_ticks)
{
    uint32_t period_us = (uint32_t)g[PI(TLP_P_PERIOD_US)];
    *period_cycles = (uint32_t)((uint64_t)period_us * clk_hz / 1000000u);
    *link_timeout_ticks = (uint32_t)g[PI(TLP_P_LINK_TIMEOUT_MS)] * 1000u / period_us;
    if (*link_timeout_ticks == 0u)
        *link_timeout_ticks = 1u;
}

TL_FOR_SIZE void tl_params_sync(tl_servo_t *s)
{
    tl_axis_cfg_t cfg;
    for (uint32_t i = 0; i < TL_AXES; i++) {
        axis_cfg(s->ax[i].p, (uint32_t)gv(s, TLP_P_PERIOD_US), s->clk_hz, &cfg);
        commit_axis(s, i, &cfg);
    }
    global_cfg(s->g, s->clk_hz, &s->period_cycles, &s->link_timeout_ticks);
    s->runaway_odd = tl_runaway_every((uint32_t)gv(s, TLP_P_PERIOD_US)) - 1u;
}

/* The parameter's index, if id names one and axis addresses it (a global one with TLP_GLOBAL_AXIS). */
static uint8_t param_slot(uint8_t axis, uint8_t id, int *k, uint8_t *why)
{
    *k = TLP_PARAM_INDEX[id];
    if (*k == IDX_NONE)
        return refuse(why, TLP_WHY_PARAM);
    if (TLP_PARAM_INFO[*k].global ? axis != TLP_GLOBAL_AXIS : axis >= TL_AXES)
        return refuse(why, axis == TLP_GLOBAL_AXIS || TLP_PARAM_INFO[*k].global ? TLP_WHY_SCOPE : TLP_WHY_AXIS);
    return TLP_ST_OK;
}

TL_FOR_SIZE uint8_t tl_param_get(const tl_servo_t *s, uint8_t axis, uint8_t id, int32_t *out, uint8_t *why)
{
    int k;
    uint8_t st = param_slot(axis, id, &k, why);
    if (st != TLP_ST_OK)
        return st;
    if (TLP_PARAM_INFO[k].global) {
        *out = s->g[k];
        return TLP_ST_OK;
    }
    const tl_axis_t *a = &s->ax[axis];
    int32_t tau = pv(a, TLP_P_TAU_MAX_MNM), cpr = pv(a, TLP_P_COUNTS_PER_REV);
    switch (id) {
    case TLP_P_KP_UNM_RAD: *out = tl_gain_phys_from_raw(pv(a, TLP_P_KP_Q16), tau, cpr); break;
    case TLP_P_KD_UNMS_RAD: *out = tl_gain_phys_from_raw(pv(a, TLP_P_KD_Q16), tau, cpr); break;
    case TLP_P_KI_UNM_RADS: *out = tl_gain_phys_from_raw(pv(a, TLP_P_KI_Q16), tau, cpr); break;
    default: *out = a->p[k]; break;
    }
    return TLP_ST_OK;
}

/* The raw gain of the largest physical gain: a larger raw gain has no
 * physical value GET could report (it would read back saturated). */
static int32_t raw_gain_max(int32_t tau, int32_t cpr) { return tl_gain_raw_from_phys(GAIN_PHYS_MAX, tau, cpr); }

static bool gains_fit(const tl_axis_t *a, int32_t tau, int32_t cpr)
{
    int32_t m = raw_gain_max(tau, cpr);
    return pv(a, TLP_P_KP_Q16) <= m && pv(a, TLP_P_KD_Q16) <= m && pv(a, TLP_P_KI_Q16) <= m;
}

/* PWM carrier CLK / (FDIV * 1023) at most max_hz. */
static bool carrier_ok(const tl_servo_t *s, int32_t fdiv, int32_t max_hz)
{
    return (uint64_t)(uint32_t)fdiv * TL_PWM_FULL * (uint32_t)max_hz >= s->clk_hz;
}

/* The bound between parameters that v for axis parameter id keeps: TLP_WHY_NONE, or the rule it breaks. */
static uint8_t axis_bound(const tl_servo_t *s, const tl_axis_t *a, uint8_t id, int32_t v)
{
    int32_t tau = pv(a, TLP_P_TAU_MAX_MNM), cpr = pv(a, TLP_P_COUNTS_PER_REV);
    switch (id) {
    case TLP_P_SOFT_MIN: return v > pv(a, TLP_P_SOFT_MAX) ? TLP_WHY_SOFT_ORDER : TLP_WHY_NONE;
    case TLP_P_SOFT_MAX: return v < pv(a, TLP_P_SOFT_MIN) ? TLP_WHY_SOFT_ORDER : TLP_WHY_NONE;
    case TLP_P_PW0: return v > pv(a, TLP_P_PWMAX) ? TLP_WHY_PW_ORDER : TLP_WHY_NONE;
    case TLP_P_PWMAX: return v < pv(a, TLP_P_PW0) ? TLP_WHY_PW_ORDER : TLP_WHY_NONE;
    case TLP_P_FDIV: return carrier_ok(s, v, gv(s, TLP_P_PWM_MAX_HZ)) ? TLP_WHY_NONE : TLP_WHY_CARRIER;
    case TLP_P_KP_Q16:
    case TLP_P_KD_Q16:
    case TLP_P_KI_Q16: return v <= raw_gain_max(tau, cpr) ? TLP_WHY_NONE : TLP_WHY_GAIN;
    case TLP_P_KP_UNM_RAD:
    case TLP_P_KD_UNMS_RAD:
    case TLP_P_KI_UNM_RADS: {
        /* a raw gain that saturated would read back as a smaller physical gain */
        int32_t raw = tl_gain_raw_from_phys(v, tau, cpr);
        return (raw == 0x7FFFFFFF && tl_gain_phys_from_raw(raw, tau, cpr) < v) ? TLP_WHY_GAIN : TLP_WHY_NONE;
    }
    case TLP_P_TAU_MAX_MNM: return gains_fit(a, v, cpr) ? TLP_WHY_NONE : TLP_WHY_GAIN;
    case TLP_P_COUNTS_PER_REV: return gains_fit(a, tau, v) ? TLP_WHY_NONE : TLP_WHY_GAIN;
    default: return TLP_WHY_NONE;
    }
}

/* The parameter's range, the tighten-only rule and the bounds between parameters;
 * TLP_ST_OK if v may be stored. */
static uint8_t param_allowed(const tl_servo_t *s, uint8_t axis, uint8_t id, int k, int32_t v, uint8_t *why)
{
    const tlp_param_info_t *info = &TLP_PARAM_INFO[k];
    if (v < info->min || v > info->max)
        return refuse(why, v < info->min ? TLP_WHY_BELOW_MIN : TLP_WHY_ABOVE_MAX);
    if (info->tighten && tl_any_enabled(s)) {
        int32_t cur = info->global ? s->g[k] : s->ax[axis].p[k];
        if (info->tighten > 0 ? v < cur : v > cur)
            return refuse(why, TLP_WHY_TIGHTEN);
    }
    if (id == TLP_P_HOME_POS && tl_any_enabled(s) && v != s->ax[axis].p[k])
        return refuse(why, TLP_WHY_HOME_POS_FROZEN);   /* the next homing would move the soft-limit window */
    if (info->global) {
        if (id == TLP_P_PWM_MAX_HZ)
            for (uint32_t i = 0; i < TL_AXES; i++)
                if (!carrier_ok(s, pv(&s->ax[i], TLP_P_FDIV), v))
                    return refuse(why, TLP_WHY_CARRIER);
        return TLP_ST_OK;
    }
    uint8_t rule = axis_bound(s, &s->ax[axis], id, v);
    return rule == TLP_WHY_NONE ? TLP_ST_OK : refuse(why, rule);
}

/* A global parameter: the new value into a copy, everything derived from it
 * worked out with interrupts on (the conversions divide), then one short
 * critical section swaps it in. */
static void set_global(tl_servo_t *s, uint8_t id, int k, int32_t v)
{
    tl_axis_cfg_t cfg[TL_AXES];
    int32_t g[TLP_PARAM_COUNT];
    for (uint32_t j = 0; j < TLP_PARAM_COUNT; j++)
        g[j] = s->g[j];
    g[k] = v;
    uint32_t period_cycles, timeout_ticks;
    global_cfg(g, s->clk_hz, &period_cycles, &timeout_ticks);
    for (uint32_t i = 0; i < TL_AXES; i++)
        axis_cfg(s->ax[i].p, (uint32_t)g[PI(TLP_P_PERIOD_US)], s->clk_hz, &cfg[i]);
    hal_irq_off();
    if (id == TLP_P_BAUD_DIV)
        s->baud_div_pending = (uint32_t)v;
    s->g[k] = v;
    for (uint32_t i = 0; i < TL_AXES; i++)
        commit_axis(s, i, &cfg[i]);
    s->period_cycles = period_cycles;
    s->link_timeout_ticks = timeout_ticks;
    s->runaway_odd = tl_runaway_every((uint32_t)g[PI(TLP_P_PERIOD_US)]) - 1u;
    hal_irq_on();
}

/* An axis parameter, the same way; a physical gain is stored as its raw gain. */
static void set_axis(tl_servo_t *s, uint8_t axis, uint8_t id, int k, int32_t v)
{
    tl_axis_t *a = &s->ax[axis];
    int32_t tau = pv(a, TLP_P_TAU_MAX_MNM), cpr = pv(a, TLP_P_COUNTS_PER_REV);
    int slot = k;
    int32_t value = v;
    switch (id) {
    case TLP_P_KP_UNM_RAD: slot = PI(TLP_P_KP_Q16); value = tl_gain_raw_from_phys(v, tau, cpr); break;
    case TLP_P_KD_UNMS_RAD: slot = PI(TLP_P_KD_Q16); value = tl_gain_raw_from_phys(v, tau, cpr); break;
    case TLP_P_KI_UNM_RADS: slot = PI(TLP_P_KI_Q16); value = tl_gain_raw_from_phys(v, tau, cpr); break;
    default: break;
    }
    int32_t p[TLP_PARAM_COUNT];
    for (uint32_t j = 0; j < TLP_PARAM_COUNT; j++)
        p[j] = a->p[j];
    p[slot] = value;
    tl_axis_cfg_t cfg;
    axis_cfg(p, (uint32_t)gv(s, TLP_P_PERIOD_US), s->clk_hz, &cfg);
    hal_irq_off();
    a->p[slot] = value;
    commit_axis(s, axis, &cfg);
    if (id == TLP_P_BRAKE && a->enabled)
        hal_pwm_enable(axis, true, v != 0);
    hal_irq_on();
}

uint8_t tl_param_set(tl_servo_t *s, uint8_t axis, uint8_t id, int32_t v, uint8_t *why)
{
    int k;
    uint8_t st = param_slot(axis, id, &k, why);
    if (st != TLP_ST_OK)
        return st;
    const tlp_param_info_t *info = &TLP_PARAM_INFO[k];
    hal_irq_off();
    st = param_allowed(s, axis, id, k, v, why);
    hal_irq_on();
    if (st != TLP_ST_OK)
        return st;
    /* A SET_PARAM thus delays the control interrupt by a few copies, not by the
     * arithmetic.  The check above stays valid meanwhile: only commands enable an
     * axis, and they run here. */
    if (info->global)
        set_global(s, id, k, v);
    else
        set_axis(s, axis, id, k, v);
    return TLP_ST_OK;
}
