/* SPDX-License-Identifier: MIT */
/* The fault latch and who may drive an axis (docs/safety.md, docs/firmware.md
 * "Safety"): disabling, enabling and clearing faults, outside the control
 * iteration (its per-period checks are safety.h).
 *  - power-up: both axes disabled; the SoC's reset-time ESTOP latch bit is
 *    acknowledged only by an ENABLE command;
 *  - every fault disables the axis in the same control period and latches a
 *    bit; only CLEAR_FAULT (when the cause is gone) clears it.  The limit-switch
 *    faults only block motion toward their end: the axis may be enabled again
 *    and driven back out;
 *  - a SoC safety latch bit is recorded as a fault of every axis it stopped
 *    before anything acknowledges it, and only the bits read are acknowledged,
 *    so no fault of one axis is lost by a command for the other. */
#include "safety.h"

void tl_axis_disable(tl_servo_t *s, uint32_t i)
{
    tl_axis_t *a = &s->ax[i];
    hal_pwm_enable(i, false, pv(a, TLP_P_BRAKE) != 0);
    hal_pwm_cmd(i, 0);
    a->enabled = false;
    a->cmd = 0;
    a->drive = false;
    if (a->home == TLP_HOME_STATE_HOMING)
        a->home = TLP_HOME_STATE_NOT_HOMED;
    tl_ctl_hold(&a->c, a->pos);
}

bool tl_any_enabled(const tl_servo_t *s)
{
    for (uint32_t i = 0; i < TL_AXES; i++)
        if (s->ax[i].enabled)
            return true;
    return false;
}

static uint16_t latch_faults(const tl_axis_t *a, uint32_t i, uint32_t safety)
{
    return latch_bridge(i, safety) | (a->enabled ? latch_enabled(safety) : 0u);
}

/* Record every latched SoC bit as a fault of the axes it stopped (those axes
 * are disabled), and return the bits read: only they may be acknowledged,
 * since a bit set after the read has not been recorded.  Interrupts off. */
uint32_t tl_fold_latch(tl_servo_t *s)
{
    uint32_t safety = hal_safety();
    for (uint32_t i = 0; i < TL_AXES; i++) {
        tl_axis_t *a = &s->ax[i];
        uint16_t f = latch_faults(a, i, safety);
        a->faults |= f;
        if (f && a->enabled)
            tl_axis_disable(s, i);
    }
    return safety & LATCH_BITS;
}

uint8_t tl_blocked(const tl_axis_t *a) { return blocked_with(a, a->faults, soft_side(a)); }

void tl_axes_disable(tl_servo_t *s, uint8_t mask)
{
    hal_irq_off();
    for (uint32_t i = 0; i < TL_AXES; i++)
        if (mask & (1u << i))
            tl_axis_disable(s, i);
    hal_irq_on();
}

/* May the axes in mask be enabled?  Acknowledges the SoC latch if so.  Interrupts off. */
static uint8_t enable_allowed(tl_servo_t *s, uint8_t mask, uint8_t *why)
{
    uint32_t latched = tl_fold_latch(s);
    for (uint32_t i = 0; i < TL_AXES; i++)
        if ((mask & (1u << i)) && (s->ax[i].faults & (uint16_t)~TLP_FAULT_DIRECTIONAL))
            return refuse(why, TLP_WHY_FAULT);
    if (hal_safety() & TL_HAL_SAFE_ESTOP_IN)
        return refuse(why, TLP_WHY_ESTOP);
    /* The SoC latch (the reset-time ESTOP, or causes now recorded as faults) is
     * acknowledged here and by CLEAR_FAULT only. */
    hal_safety_ack(latched);
    if (hal_safety() & TL_HAL_SAFE_FORCED)
        return refuse(why, TLP_WHY_FORCED);
    return TLP_ST_OK;
}

/* Enable the axes in mask (each holds where it is: no jump). */
uint8_t tl_axes_enable(tl_servo_t *s, uint8_t mask, uint8_t *why)
{
    hal_irq_off();
    uint8_t st = enable_allowed(s, mask, why);
    if (st != TLP_ST_OK) {
        hal_irq_on();
        return st;
    }
    for (uint32_t i = 0; i < TL_AXES; i++) {
        if (!(mask & (1u << i)) || s->ax[i].enabled)
            continue;
        tl_axis_t *a = &s->ax[i];
        tl_enc_sample_t e;
        hal_enc_read(i, &e);
        a->pos = wrap_add(e.pos, a->offset);
        tl_ctl_reset(&a->c, a->pos, e.now);   /* set-point = where it is: no jump */
        a->recover = soft_side(a);
        a->stall_dir = 0;
        enc_check_reset(a);
        a->cmd = 0;
        a->enabled = true;
        hal_pwm_cmd(i, 0);
        hal_pwm_enable(i, true, pv(a, TLP_P_BRAKE) != 0);
    }
    s->link_idle_ticks = 0;
    hal_irq_on();
    return TLP_ST_OK;
}

/* The faults of axis i whose cause is present now (CLEAR_FAULT keeps them). */
static uint16_t faults_present(const tl_axis_t *a, uint32_t i, uint32_t safety)
{
    tl_enc_sample_t e;
    hal_enc_read(i, &e);
    uint16_t keep = 0;
    if (safety & TL_HAL_SAFE_ESTOP_IN)
        keep |= TLP_FAULT_ESTOP;
    if (e.bridge_fault)
        keep |= TLP_FAULT_BRIDGE;
    uint8_t lim = pv(a, TLP_P_LIMIT_SW) ? e.limits : 0u;
    if (lim & TLP_LIMIT_NEG)
        keep |= TLP_FAULT_LIMIT_NEG;
    if (lim & TLP_LIMIT_POS)
        keep |= TLP_FAULT_LIMIT_POS;
    return keep;
}

/* Clear the faults of the axes in mask whose cause is gone; TLP_ST_STATE if any is left. */
uint8_t tl_axes_clear(tl_servo_t *s, uint8_t mask, uint8_t *why)
{
    bool left = false;
    hal_irq_off();
    uint32_t latched = tl_fold_latch(s);
    uint32_t safety = hal_safety();
    for (uint32_t i = 0; i < TL_AXES; i++) {
        if (!(mask & (1u << i)))
            continue;
        tl_axis_t *a = &s->ax[i];
        uint16_t keep = faults_present(a, i, safety);
        if (a->faults & TLP_FAULT_ENCODER) {
            hal_enc_clear_illegal(i);
            a->illegal_seen = 0;
        }
        a->faults &= keep;
        left = left || a->faults;
    }
    if (!(safety & TL_HAL_SAFE_ESTOP_IN))
        hal_safety_ack(latched);
    hal_irq_on();
    return left ? refuse(why, TLP_WHY_CAUSE) : TLP_ST_OK;
}
