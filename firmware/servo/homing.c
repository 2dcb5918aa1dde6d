/* SPDX-License-Identifier: MIT */
/* Homing (HOME, docs/firmware.md "Homing"): SEEK the switch at HOME_VEL, SETTLE
 * on it, (CREEP back onto it if the stop bounced off), BACK OFF until it closes,
 * (on to the INDEX).  The final approach runs at HOME_VEL >> HOME_SLOW_SHIFT:
 * the switch is sampled once per period, so the slower the approach, the more
 * repeatable the home point.  tl_home_tick runs inside the control iteration of
 * a homing axis. */
#include "servo_internal.h"

enum { HOME_SEEK, HOME_SETTLE, HOME_CREEP, HOME_BACKOFF, HOME_INDEX };

/* Home point found at position ref: from now on it reads HOME_POS, and the
 * controller holds where the axis is, in the new coordinates. */
static void home_finish(tl_axis_t *a, int32_t ref, uint32_t now)
{
    int32_t delta = (int32_t)((uint32_t)pv(a, TLP_P_HOME_POS) - (uint32_t)ref);
    a->offset = wrap_add(a->offset, delta);
    a->pos = wrap_add(a->pos, delta);
    a->stall_dir = 0;
    tl_ctl_reset(&a->c, a->pos, now);
    a->home = TLP_HOME_STATE_HOMED;
}

/* One period of homing (the phases above); the point found reads HOME_POS. */
void tl_home_tick(tl_axis_t *a, uint32_t i, uint32_t now)
{
    uint8_t sw = a->home_dir < 0 ? TLP_LIMIT_NEG : TLP_LIMIT_POS;
    bool open = (a->limits & sw) != 0u;
    int64_t fast = a->home_step_q16, slow = a->home_step_q16 >> HOME_SLOW_SHIFT;
    int64_t step;   /* set-point motion this period, toward the switch (negative: away) */
    switch (a->home_phase) {
    case HOME_SEEK:
    case HOME_CREEP:
        if (open) {
            tl_ctl_hold(&a->c, a->pos);
            a->home_sp_q16 = (int64_t)a->pos * 65536;
            a->home_phase = HOME_SETTLE;
            return;
        }
        step = a->home_phase == HOME_SEEK ? fast : slow;
        break;
    case HOME_SETTLE: {
        int64_t v = a->c.vel_q8 < 0 ? -(int64_t)a->c.vel_q8 : a->c.vel_q8;
        if (v > (int64_t)pv(a, TLP_P_HOME_VEL) * (256 >> HOME_SLOW_SHIFT))
            return;   /* still moving: hold */
        tl_ctl_hold(&a->c, a->pos);   /* the slow approach starts where the axis came to rest */
        a->home_sp_q16 = (int64_t)a->pos * 65536;
        a->home_phase = open ? HOME_BACKOFF : HOME_CREEP;
        return;
    }
    case HOME_BACKOFF:
        if (!open) {
            if (!a->home_index) {
                home_finish(a, a->pos, now);
                return;
            }
            hal_enc_index_arm(i);
            a->home_phase = HOME_INDEX;
        }
        step = -slow;
        break;
    default: {
        int32_t ip;
        if (hal_enc_index(i, &ip)) {
            home_finish(a, wrap_add(ip, a->offset), now);
            return;
        }
        step = -slow;
        break;
    }
    }
    a->home_sp_q16 += a->home_dir < 0 ? -step : step;
    tl_ctl_move(&a->c, (int32_t)(a->home_sp_q16 >> 16), false);
}

uint8_t tl_home_start(tl_servo_t *s, uint8_t axis, uint8_t mode, uint8_t index, uint8_t *why)
{
    if (axis >= TL_AXES)
        return refuse(why, TLP_WHY_AXIS);
    if (mode > TLP_HOME_MODE_HERE || index > 1u)
        return refuse(why, TLP_WHY_CHOICE);
    tl_axis_t *a = &s->ax[axis];
    if (a->home == TLP_HOME_STATE_HOMING)
        return refuse(why, TLP_WHY_HOMING);
    hal_irq_off();
    if (mode == TLP_HOME_MODE_HERE) {
        tl_enc_sample_t e;
        hal_enc_read(axis, &e);
        a->pos = wrap_add(e.pos, a->offset);
        home_finish(a, a->pos, e.now);
        hal_irq_on();
        return TLP_ST_OK;
    }
    if (!a->enabled || a->faults || !pv(a, TLP_P_LIMIT_SW)) {
        hal_irq_on();
        return refuse(why, !a->enabled ? TLP_WHY_DISABLED
                           : (a->faults ? TLP_WHY_FAULT : TLP_WHY_NO_SWITCHES));
    }
    a->home = TLP_HOME_STATE_HOMING;
    a->home_phase = HOME_SEEK;
    a->home_dir = mode == TLP_HOME_MODE_NEG ? -1 : 1;
    a->home_index = index != 0u;
    a->home_sp_q16 = (int64_t)a->pos * 65536;
    tl_ctl_hold(&a->c, a->pos);
    hal_irq_on();
    return TLP_ST_OK;
}

