/* SPDX-License-Identifier: MIT */
/* Open-loop drive (DRIVE, docs/protocol.md): a fixed, signed PWM command on
 * an enabled axis, for bring-up (the encoder-sign check before the loop is
 * closed, docs/hardware.md) and for the characterisation's duty sweeps.
 * Nothing else changes: the control iteration (servo.c, axis_tick) still runs
 * every check on the axis - RUNAWAY with the open-loop command, the limit
 * switches and their direction block, the soft limits, the link watchdog, the
 * e-stop and the SoC latch - and any fault, DISABLE, STOP, MOVE or HOME ends
 * the drive.  The set-point follows the position while it lasts, so the
 * following-error check sees nothing to follow and a STOP holds where the
 * axis is. */
#include "servo_internal.h"

uint8_t tl_drive_start(tl_servo_t *s, uint8_t axis, int32_t duty, uint8_t *why)
{
    if (axis >= TL_AXES)
        return refuse(why, TLP_WHY_AXIS);
    tl_axis_t *a = &s->ax[axis];
    int32_t limit = pv(a, TLP_P_CMD_LIMIT);
    if (duty > limit || duty < -limit)
        return refuse(why, TLP_WHY_CMD_LIMIT);
    hal_irq_off();
    uint8_t st = TLP_ST_OK;
    uint8_t b = tl_blocked(a);
    if (!a->enabled)
        st = refuse(why, TLP_WHY_DISABLED);
    else if (a->home == TLP_HOME_STATE_HOMING)
        st = refuse(why, TLP_WHY_HOMING);
    else if (hal_safety() & TL_HAL_SAFE_FORCED)
        st = refuse(why, TLP_WHY_FORCED);
    else if (((b & TLP_LIMIT_NEG) && duty < 0) || ((b & TLP_LIMIT_POS) && duty > 0))
        st = refuse(why, TLP_WHY_LIMIT);
    if (st == TLP_ST_OK) {
        if (!a->drive)
            tl_ctl_hold(&a->c, a->pos);
        a->drive_duty = (int16_t)duty;
        a->drive = true;
    }
    hal_irq_on();
    return st;
}
