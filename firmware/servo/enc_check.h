/* SPDX-License-Identifier: MIT */
/* Encoder plausibility (docs/safety.md, RUNAWAY): does the encoder show the
 * motion the command drives?  Independent of STALL_CMD, at any command
 * above the motor's breakaway ENC_CMD0.
 *
 * The model: a DC motor's steady speed grows linearly with the command above
 * its breakaway (back-EMF balances the drive voltage), v_ss = ENC_CPS *
 * (|cmd| - ENC_CMD0) / 1023 counts/s, reached with the mechanical time
 * constant.  What the check asks of the encoder is a lower bound of that:
 * half the steady speed, approached at the slowest (time constant
 * ENC_TAU_MS) but given up at once (an axis may stop as fast as it likes),
 * starting from the speed measured when the command entered this direction
 * (so braking from the other direction counts as the deceleration it is,
 * and asks nothing of the encoder until that bound turns the command's way).
 * The distance that lower-bound speed covers is compared with the encoder's
 * progress in the command's direction, period by period: what the encoder
 * falls behind adds up, what it gets ahead is dropped, so no earlier motion
 * can hide a later loss.  Behind by more than ENC_SLACK counts: RUNAWAY.
 * A frozen, reversed, undercounting or chattering encoder never keeps up;
 * a healthy one on a plant that reaches half the model's speed always does.
 *
 * Per period a few multiplies and compares: no division in the interrupt
 * (the constants are derived in enc_check_derive, outside it). */
#ifndef TL_ENC_CHECK_H
#define TL_ENC_CHECK_H

#include <stdint.h>

#include "servo.h"

/* Constants of one axis from ENC_CPS, ENC_TAU_MS (both >= 1) and the
 * period; divides (unsigned: no signed 64-bit division from libgcc), so it
 * runs outside the interrupt. */
static inline void enc_check_derive(tl_enc_cfg_t *e, int32_t cps, int32_t tau_ms, uint32_t period_us)
{
    /* half the model's speed per command step, counts/s q8 */
    e->k_q8 = (int32_t)(((uint64_t)(uint32_t)cps * 256u) / (2u * TL_PWM_FULL));
    uint64_t alpha = ((uint64_t)period_us << 16) / ((uint64_t)(uint32_t)tau_ms * 1000u);
    e->alpha_q16 = alpha > 65536u ? 65536 : (int32_t)alpha;
    e->dt_q16 = (int32_t)(((uint64_t)period_us << 16) / 1000000u);
}

/* Start the comparison again (enabled, homed, or the command's direction changed). */
static inline void enc_check_reset(tl_axis_t *a) { a->enc_dir = 0; }

/* One period: the command applied during it (a->cmd), the position and the
 * measured speed at its end.  Returns TLP_FAULT_RUNAWAY or 0.
 *
 * 32-bit where the ranges allow (docs/firmware.md, "Timing"): the speed
 * estimate is within +-(2^31 - 1) (control_step.h saturates it there), the
 * model's speed (|cmd| - ENC_CMD0) k_q8 <= 1023 * ENC_CPS_max 256 / 2046 < 2^31,
 * and the lower bound always lies between the two, so it is 32-bit too; only
 * the distance it covers (up to ENC_SLACK 2^24 and a period's worth beyond)
 * needs 64 bits. */
static inline __attribute__((always_inline)) uint16_t enc_check(tl_axis_t *a, int32_t cmd0, int32_t slack)
{
    /* what it reads first: the tests and products would otherwise wait for the loads (2 cycles
     * on tl_cpu_pipe) */
    int32_t cmd = a->cmd, vlo = a->enc_vlo_q8, k_q8 = a->enc.k_q8;
    int8_t edir = a->enc_dir;
    int8_t dir = cmd > cmd0 ? 1 : (cmd < -cmd0 ? -1 : 0);
    if (TL_UNLIKELY(dir == 0 || dir != edir)) {
        a->enc_dir = dir;
        a->enc_ref = a->pos;
        a->enc_exp_q24 = 0;
        a->enc_vlo_q8 = dir < 0 ? -a->c.vel_q8 : (dir ? a->c.vel_q8 : 0);
        return 0;
    }
    int32_t v_ss = ((dir > 0 ? cmd : -cmd) - cmd0) * k_q8;
    if (v_ss <= vlo) {
        vlo = v_ss;
    } else {
        /* v_ss - vlo in (0, 2^32): exact as an unsigned difference; times alpha over 2^16 it
         * is at most the difference, so vlo stays between its old value and v_ss */
        uint32_t gap = (uint32_t)v_ss - (uint32_t)vlo;
        vlo = (int32_t)((uint32_t)vlo + (uint32_t)(((uint64_t)gap * (uint32_t)a->enc.alpha_q16) >> 16));
    }
    a->enc_vlo_q8 = vlo;
    if (TL_UNLIKELY(vlo <= 0)) {
        /* still braking from the other direction: the speed estimate lags the
         * reversal, so nothing is asked of the encoder until the lower bound
         * says the axis must move the command's way */
        a->enc_ref = a->pos;
        a->enc_exp_q24 = 0;
        return 0;
    }
    /* 0 < vlo < 2^31, dt_q16 < 2^11 (PERIOD_US <= 25 000): one 32 x 32-bit unsigned product */
    int64_t exp = a->enc_exp_q24 + (int64_t)((uint64_t)(uint32_t)vlo * (uint32_t)a->enc.dt_q16);
    int32_t moved = (int32_t)((uint32_t)a->pos - (uint32_t)a->enc_ref);
    uint32_t dm = (uint32_t)((int32_t)dir >> 31);   /* -moved against the + direction; no branch */
    moved = (int32_t)(((uint32_t)moved ^ dm) - dm);
    a->enc_ref = a->pos;
    /* what the encoder is behind the lower bound; ahead of it counts for nothing later */
    int64_t behind = exp - (int64_t)((uint64_t)(int64_t)moved << 24);
    a->enc_exp_q24 = behind & ~(behind >> 63);   /* max(behind, 0) without a branch: a healthy axis is ahead */
    /* behind > slack: the sign of their difference (both well inside 2^62) */
    return (uint16_t)(((uint64_t)(((int64_t)slack << 24) - behind) >> 63) * TLP_FAULT_RUNAWAY);
}

#endif
