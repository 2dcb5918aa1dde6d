/* SPDX-License-Identifier: MIT */
/* The accessors of hal.h that the control iteration calls for every axis and
 * period, on the torqueloop SoC: static inline (included by hal.h when
 * TL_HAL_SOC_INLINE is defined, as the servo image's build does), so that the
 * iteration, written out for each axis, reads and writes its registers at
 * constant addresses without a call (docs/firmware.md, "Timing").  The decoder
 * read is hal_enc_read_inline there and an ordinary function (hal_soc.c) for
 * the other callers, whose copies would not fit the factory slot. */
#ifndef TL_HAL_SOC_INLINE_H
#define TL_HAL_SOC_INLINE_H

#include "torqueloop_regs.h"

/* Axis register of axis i: the AXIS0 offset moved to that axis's page. */
#define AX(i, REG) TL_REG32(((i) ? TL_AXIS1_BASE : TL_AXIS0_BASE) + (TL_AXIS0_##REG##_ADDR - TL_AXIS0_BASE))

/* One reading of the decoder; false if a count fell between the two edge-time reads. */
static inline __attribute__((always_inline)) bool hal_enc_read_once(uint32_t axis, tl_enc_sample_t *s)
{
    uint32_t t0 = AX(axis, ENC_EDGE_TIME);
    s->pos = (int32_t)AX(axis, ENC_POS);
    s->interval = AX(axis, ENC_EDGE_INTERVAL);
    uint32_t t1 = AX(axis, ENC_EDGE_TIME);
    s->edge_time = t1;
    s->now = AX(axis, ENC_TIMESTAMP);
    s->illegal = AX(axis, ENC_ILLEGAL) & TL_AXIS_ENC_ILLEGAL_COUNT_MSK;
    uint32_t st = AX(axis, PWM_STATUS);
    s->bridge_fault = (st & TL_AXIS_PWM_STATUS_BRIDGE_FAULT_MSK) != 0u;
    s->limits = (uint8_t)(((st & TL_AXIS_PWM_STATUS_LIM_NEG_MSK) ? TL_HAL_LIM_NEG : 0u) |
                          ((st & TL_AXIS_PWM_STATUS_LIM_POS_MSK) ? TL_HAL_LIM_POS : 0u));
    return t0 == t1;
}

static inline __attribute__((always_inline)) void hal_enc_read_inline(uint32_t axis, tl_enc_sample_t *s)
{
    /* Position and edge time are two reads: read again if a count fell between them,
     * so the pair always belongs to the same edge.  The first reading straight through
     * and the retry out of the way: a loop's back edge not taken costs a misprediction. */
    if (__builtin_expect(!hal_enc_read_once(axis, s), 0))
        while (!hal_enc_read_once(axis, s)) {
        }
}

static inline __attribute__((always_inline)) void hal_pwm_cmd(uint32_t axis, int32_t cmd)
{
    AX(axis, PWM_CMD) = (uint32_t)cmd & TL_AXIS_PWM_CMD_CMD_MSK;
}

/* The register's bits 0-1 are FORCED and ESTOP_IN, bits 8-11 the latch bits in hal.h's order:
 * two masks and a shift instead of a test per bit. */
_Static_assert(TL_SYS_SAFETY_SAFE_MSK == TL_HAL_SAFE_FORCED && TL_SYS_SAFETY_ESTOP_IN_MSK == TL_HAL_SAFE_ESTOP_IN,
               "SYS.SAFETY bits 0-1");
_Static_assert((TL_SYS_SAFETY_ESTOP_MSK >> 6) == TL_HAL_SAFE_ESTOP && (TL_SYS_SAFETY_FAULT0_MSK >> 6) == TL_HAL_SAFE_FAULT0 &&
               (TL_SYS_SAFETY_FAULT1_MSK >> 6) == TL_HAL_SAFE_FAULT1 && (TL_SYS_SAFETY_WDOG_MSK >> 6) == TL_HAL_SAFE_WDOG,
               "SYS.SAFETY bits 8-11");
static inline __attribute__((always_inline)) uint32_t hal_safety(void)
{
    uint32_t r = TL_SYS_SAFETY;
    return (r & (TL_HAL_SAFE_FORCED | TL_HAL_SAFE_ESTOP_IN)) |
           ((r >> 6) & (TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG));
}

#endif
