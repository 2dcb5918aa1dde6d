/* SPDX-License-Identifier: MIT */
/* What the files of the servo core share among themselves; code outside
 * firmware/servo/ uses servo.h.  The core is cut along its seams:
 *   servo.c     start-up and the control iteration (tl_servo_tick, the hot path)
 *   safety.h    the per-period checks the iteration inlines
 *   safety.c    the fault latch, enabling, disabling and clearing
 *   params.c    parameters, their rules, and what they give the iteration
 *   homing.c    the homing sequence
 *   commands.c  the link: the command table (generated rows) and one cmd_* per command */
#ifndef TL_SERVO_INTERNAL_H
#define TL_SERVO_INTERNAL_H

#include "hal.h"
#include "servo.h"
#include "enc_check.h"

#define IDX_NONE (-1)
#define PI(id) TLP_PARAM_INDEX[id]

/* TLP_PARAM_INDEX is a constant table: with a constant id each read is one load. */
static inline int32_t pv(const tl_axis_t *a, uint8_t id) { return a->p[TLP_PARAM_INDEX[id]]; }
static inline int32_t gv(const tl_servo_t *s, uint8_t id) { return s->g[TLP_PARAM_INDEX[id]]; }

/* Positions wrap modulo 2^32 like the decoder's counter: no signed overflow. */
static inline int32_t wrap_add(int32_t x, int32_t y) { return (int32_t)((uint32_t)x + (uint32_t)y); }

static inline bool axis_mask_ok(uint8_t m) { return m != 0u && (m & ~((1u << TL_AXES) - 1u)) == 0u; }

/* A refusal: the rule (TLP_WHY_*, the reply's second byte) into *why; returns the
 * status protocol.toml gives that rule. */
static inline uint8_t refuse(uint8_t *why, uint8_t rule)
{
    *why = rule;
    return tlp_why_status(rule);
}

/* ---- params.c ---- */

/* What an axis's parameters and the period give the control iteration. */
typedef struct {
    tl_ctl_params_t ctl;
    tl_ctl_derived_t d;
    uint32_t stall_limit_ticks;   /* STALL_MS in periods, rounded up */
    int64_t home_step_q16;        /* HOME_VEL per period, q16 counts */
    tl_enc_cfg_t enc;             /* encoder plausibility */
} tl_axis_cfg_t;

/* Every parameter's default, then what they give the iteration (start-up). */
void tl_params_defaults(tl_servo_t *s);
void tl_params_sync(tl_servo_t *s);
/* The functions that may refuse return the status and put the rule (TLP_WHY_*) into *why. */
uint8_t tl_param_get(const tl_servo_t *s, uint8_t axis, uint8_t id, int32_t *out, uint8_t *why);
/* Store v if every rule allows it. */
uint8_t tl_param_set(tl_servo_t *s, uint8_t axis, uint8_t id, int32_t v, uint8_t *why);

/* ---- safety.c ---- */

void tl_axis_disable(tl_servo_t *s, uint32_t i);
uint32_t tl_fold_latch(tl_servo_t *s);
bool tl_any_enabled(const tl_servo_t *s);
uint8_t tl_blocked(const tl_axis_t *a);
uint8_t tl_axes_enable(tl_servo_t *s, uint8_t mask, uint8_t *why);
void tl_axes_disable(tl_servo_t *s, uint8_t mask);
uint8_t tl_axes_clear(tl_servo_t *s, uint8_t mask, uint8_t *why);

/* ---- homing.c ---- */

/* The final approach runs at HOME_VEL >> HOME_SLOW_SHIFT (homing.c). */
#define HOME_SLOW_SHIFT 4

/* Periods shorter than this run each axis's runaway checks (stall_check and
 * enc_check, safety.h) every other period, the two axes in turn, with their
 * constants derived for two periods: what keeps the control iteration within
 * its cycle budget at 20 kHz (docs/firmware.md, "Timing"); the reaction time
 * this costs is at most one period more (docs/safety.md, "Runaway at 20 kHz"). */
#define TL_RUNAWAY_EVERY_OTHER_BELOW_US 100u
/* Control periods from one runaway check of an axis to its next. */
static inline uint32_t tl_runaway_every(uint32_t period_us) { return period_us < TL_RUNAWAY_EVERY_OTHER_BELOW_US ? 2u : 1u; }
void tl_home_tick(tl_axis_t *a, uint32_t i, uint32_t now);
uint8_t tl_home_start(tl_servo_t *s, uint8_t axis, uint8_t mode, uint8_t index, uint8_t *why);

#endif
