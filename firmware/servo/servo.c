/* SPDX-License-Identifier: MIT */
/* Servo application core (servo.h): parameters, safety and the command
 * handler.  A command that changes the machine runs only with a MAC of the
 * open session (tl_auth.h, docs/security.md); reading, STOP and disabling
 * need none.  The safety rules (docs/safety.md, docs/firmware.md "Safety"):
 *  - power-up: both axes disabled; the SoC's reset-time ESTOP latch bit is
 *    acknowledged only by an ENABLE command;
 *  - every fault (docs/protocol.md, "Fault flags") disables the axis in the
 *    same control period and latches a bit; only CLEAR_FAULT (when the cause
 *    is gone) clears it.  The limit-switch faults only block motion toward
 *    their end: the axis may be enabled again and driven back out;
 *  - a SoC safety latch bit is recorded as a fault of every axis it stopped
 *    before anything acknowledges it, and only the bits read are
 *    acknowledged, so no fault of one axis is lost by a command for the other;
 *  - a safety limit (a tighten-only parameter) can only be made stricter while
 *    any axis is enabled;
 *  - only commands that show the host in control feed the link watchdog;
 *  - a frame that fails any check, or a replayed one, is counted and answered
 *    with an error and changes nothing. */
#include "servo.h"

#include "control_step.h"
#include "hal.h"
#include "store.h"

#define IDX_NONE (-1)
#define LATCH_BITS (TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG)
/* Largest physical gain (KP_UNM_RAD, KD_UNMS_RAD, KI_UNM_RADS share the range). */
#define GAIN_PHYS_MAX 100000000
_Static_assert(TL_HAL_LIM_NEG == TLP_LIMIT_NEG && TL_HAL_LIM_POS == TLP_LIMIT_POS, "limit bits");

/* Homing: SEEK the switch at HOME_VEL, SETTLE on it, (CREEP back onto it if
 * the stop bounced off), BACK OFF until it closes, (on to the INDEX).  The
 * final approach runs at a sixteenth of HOME_VEL: the switch is sampled once
 * per period, so the slower the approach, the more repeatable the home point. */
enum { HOME_SEEK, HOME_SETTLE, HOME_CREEP, HOME_BACKOFF, HOME_INDEX };
#define HOME_SLOW_SHIFT 4

int tl_param_index(uint8_t id) { return TLP_PARAM_INDEX[id]; }
void tl_param_range(uint32_t k, int32_t *lo, int32_t *hi)
{
    *lo = TLP_PARAM_INFO[k].min;
    *hi = TLP_PARAM_INFO[k].max;
}

/* TLP_PARAM_INDEX is a constant table: with a constant id each read is one load. */
static inline int32_t pv(const tl_axis_t *a, uint8_t id) { return a->p[TLP_PARAM_INDEX[id]]; }
static inline int32_t gv(const tl_servo_t *s, uint8_t id) { return s->g[TLP_PARAM_INDEX[id]]; }

/* Positions wrap modulo 2^32 like the decoder's counter: no signed overflow. */
static inline int32_t wrap_add(int32_t x, int32_t y) { return (int32_t)((uint32_t)x + (uint32_t)y); }

/* What an axis's parameters and the period give the control iteration. */
typedef struct {
    tl_ctl_params_t ctl;
    tl_ctl_derived_t d;
    uint32_t stall_limit_ticks;   /* STALL_MS in periods, rounded up */
    int64_t home_step_q16;        /* HOME_VEL per period, q16 counts */
} axis_cfg_t;

#define PI(id) TLP_PARAM_INDEX[id]

/* From a parameter array; divides, so it runs with interrupts on. */
TL_FOR_SIZE static void axis_cfg(const int32_t *p, uint32_t period_us, uint32_t clk_hz, axis_cfg_t *out)
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
    tl_ctl_derived(&out->d, &out->ctl, period_us, clk_hz);
    out->stall_limit_ticks = ((uint32_t)p[PI(TLP_P_STALL_MS)] * 1000u + period_us - 1u) / period_us;
    /* counts/s * us * 2^16 / 1e6 = x * 1024 / 15625, as control.c's vmax; HOME_VEL >= 1, so
     * unsigned (the image then needs no signed 64-bit division from libgcc) */
    out->home_step_q16 = (int64_t)((uint64_t)(uint32_t)p[PI(TLP_P_HOME_VEL)] * period_us * 1024u / 15625u);
    if (out->home_step_q16 < (1 << HOME_SLOW_SHIFT))
        out->home_step_q16 = 1 << HOME_SLOW_SHIFT;
}

/* Hand a configuration to the control iteration: copies, for a critical section. */
static void commit_axis(tl_servo_t *s, uint32_t i, const axis_cfg_t *cfg)
{
    tl_axis_t *a = &s->ax[i];
    a->ctl = cfg->ctl;
    tl_ctl_apply(&a->c, &cfg->d);
    a->stall_limit_ticks = cfg->stall_limit_ticks;
    a->home_step_q16 = cfg->home_step_q16;
    hal_pwm_config(i, (uint32_t)pv(a, TLP_P_FDIV), (uint32_t)pv(a, TLP_P_PW0), (uint32_t)pv(a, TLP_P_PWMAX));
    hal_limit_block(i, pv(a, TLP_P_LIMIT_SW) != 0);
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

TL_FOR_SIZE static void sync_all(tl_servo_t *s)
{
    axis_cfg_t cfg;
    for (uint32_t i = 0; i < TL_AXES; i++) {
        axis_cfg(s->ax[i].p, (uint32_t)gv(s, TLP_P_PERIOD_US), s->clk_hz, &cfg);
        commit_axis(s, i, &cfg);
    }
    global_cfg(s->g, s->clk_hz, &s->period_cycles, &s->link_timeout_ticks);
}

static void disable_axis(tl_servo_t *s, uint32_t i)
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
    a->c.cmd = 0;
}

static bool any_enabled(const tl_servo_t *s)
{
    for (uint32_t i = 0; i < TL_AXES; i++)
        if (s->ax[i].enabled)
            return true;
    return false;
}

/* Faults the SoC safety latch bits mean for axis i: its own bridge bit always
 * (a bridge fault is a fault of that axis whatever it was doing), the shared
 * e-stop and watchdog bits for an axis they stopped (enabled). */
static inline __attribute__((always_inline)) uint16_t latch_bridge(uint32_t i, uint32_t safety)
{
    return (safety & (i == 0u ? TL_HAL_SAFE_FAULT0 : TL_HAL_SAFE_FAULT1)) ? TLP_FAULT_BRIDGE : 0u;
}
static inline __attribute__((always_inline)) uint16_t latch_enabled(uint32_t safety)
{
    return (uint16_t)(((safety & TL_HAL_SAFE_ESTOP) ? TLP_FAULT_ESTOP : 0u) |
                      ((safety & TL_HAL_SAFE_WDOG) ? TLP_FAULT_HW_SAFE : 0u));
}
static uint16_t latch_faults(const tl_axis_t *a, uint32_t i, uint32_t safety)
{
    return latch_bridge(i, safety) | (a->enabled ? latch_enabled(safety) : 0u);
}

/* The soft-limit side the position is beyond (SOFT_MIN <= SOFT_MAX: at most one). */
static inline __attribute__((always_inline)) uint8_t soft_side(const tl_axis_t *a)
{
    return a->pos < pv(a, TLP_P_SOFT_MIN) ? TLP_LIMIT_NEG : (a->pos > pv(a, TLP_P_SOFT_MAX) ? TLP_LIMIT_POS : 0u);
}

/* Record every latched SoC bit as a fault of the axes it stopped (those axes
 * are disabled), and return the bits read: only they may be acknowledged,
 * since a bit set after the read has not been recorded.  Interrupts off. */
static uint32_t fold_latch(tl_servo_t *s)
{
    uint32_t safety = hal_safety();
    for (uint32_t i = 0; i < TL_AXES; i++) {
        tl_axis_t *a = &s->ax[i];
        uint16_t f = latch_faults(a, i, safety);
        a->faults |= f;
        if (f && a->enabled)
            disable_axis(s, i);
    }
    return safety & LATCH_BITS;
}

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

TL_FOR_SIZE void tl_servo_init(tl_servo_t *s)
{
    s->clk_hz = hal_clk_hz();
    for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++)
        s->g[k] = TLP_PARAM_INFO[k].dflt[0];
#ifdef TL_DEFAULT_PERIOD_US
    s->g[tl_param_index(TLP_P_PERIOD_US)] = TL_DEFAULT_PERIOD_US;
#endif
#ifdef TL_DEFAULT_BAUD_DIV
    s->g[tl_param_index(TLP_P_BAUD_DIV)] = TL_DEFAULT_BAUD_DIV;
#endif
    tl_rx_init(&s->rx);
    s->seq.any = false;
    s->seq.last = 0;
    s->cnt = (tl_counters_t){0};
    s->ticks = 0;
    s->link_idle_ticks = 0;
    s->telem_every = 0;
    s->telem_phase = 0;
    s->telem_seq = 0;
    s->telem_due = false;
    s->bootloader_req = false;
    s->baud_div_pending = 0;
    s->loop_cycles_max = 0;
    s->jitter_cycles_max = 0;
    for (uint32_t i = 0; i < TL_AXES; i++) {
        tl_axis_t *a = &s->ax[i];
        /* Per-axis defaults from the protocol definition, which takes them from
           torqueloop/spec/system.toml: the paper's Table 1 P gains, tau_max and
           carrier of this axis's motor. */
        for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++)
            a->p[k] = TLP_PARAM_INFO[k].dflt[i];
        tl_enc_sample_t e;
        hal_enc_read(i, &e);
        a->pos = e.pos;
        a->offset = 0;
        a->illegal_seen = e.illegal;
        a->faults = 0;
        a->cmd = 0;
        a->limits = 0;
        a->recover = 0;
        a->home = TLP_HOME_STATE_NOT_HOMED;
        a->stall_dir = 0;
        a->drive = false;
        a->drive_duty = 0;
        tl_ctl_reset(&a->c, e.pos, e.now);
    }
    tl_store_load(s);   /* the saved parameters over the defaults (store.c) */
    sync_all(s);
    for (uint32_t i = 0; i < TL_AXES; i++)
        disable_axis(s, i);
    hal_set_baud_div((uint32_t)gv(s, TLP_P_BAUD_DIV));
    /* The key last: its HMAC states cost ~55 000 cycles, and the link rate is set before them. */
    tl_auth_init(&s->auth, hal_key_slot());
}

uint32_t tl_servo_period_cycles(const tl_servo_t *s) { return s->period_cycles; }


/* Runaway / encoder loss.  A command of STALL_CMD or more must, within
 * STALL_MS, either move the position past a reference in its direction or
 * raise the velocity in its direction by STALL_DV_Q8 over a reference; each
 * time it does, the references move up to where the axis is.  An axis that
 * accelerates, cruises, or is braked from the other direction satisfies it
 * every few periods; a frozen encoder, one that counts the wrong way (the
 * measured motion runs away against the command) or one channel flickering
 * never does.  A compare and a counter per period: no division, no history. */
#define STALL_DV_Q8 (20 * 256)   /* 20 counts/s */
static inline __attribute__((always_inline)) uint16_t stall_check(tl_axis_t *a)
{
    int32_t lim = pv(a, TLP_P_STALL_CMD);
    int8_t dir = a->cmd >= lim ? 1 : (a->cmd <= -lim ? -1 : 0);
    if (dir == 0 || dir != a->stall_dir) {
        a->stall_dir = dir;
        a->stall_ref = a->pos;
        a->stall_vel_q8 = a->c.vel_q8;
        a->stall_ticks = 0;
        return 0;
    }
    /* each reference only ever moves on in dir */
    int32_t moved = (int32_t)((uint32_t)a->pos - (uint32_t)a->stall_ref);
    int64_t dv = (int64_t)a->c.vel_q8 - a->stall_vel_q8;
    bool progress = false;
    if (dir > 0 ? moved > 0 : moved < 0) {
        a->stall_ref = a->pos;
        progress = true;
    }
    if (dir > 0 ? dv > STALL_DV_Q8 : dv < -STALL_DV_Q8) {
        a->stall_vel_q8 = a->c.vel_q8;
        progress = true;
    }
    if (progress) {
        a->stall_ticks = 0;
        return 0;
    }
    return ++a->stall_ticks >= a->stall_limit_ticks ? TLP_FAULT_RUNAWAY : 0u;
}

/* The switch homing is looking for does not trip a limit fault. */
static uint8_t home_switch(const tl_axis_t *a)
{
    if (a->home != TLP_HOME_STATE_HOMING)
        return 0;
    return a->home_dir < 0 ? TLP_LIMIT_NEG : TLP_LIMIT_POS;
}

/* What the SoC safety word means this period, worked out once for both axes. */
typedef struct {
    uint32_t safety;
    uint16_t all;        /* faults of every axis: the e-stop input */
    uint16_t enabled;    /* faults of an enabled axis: the latched e-stop and watchdog bits */
    bool link;           /* the link watchdog expired (enabled axes) */
} tick_faults_t;

/* Every check of one axis for this period; returns the faults that tripped.
 * *out: the soft-limit sides the position is beyond (enabled axes only). */
static inline __attribute__((always_inline)) uint16_t axis_checks(tl_axis_t *a, uint32_t i,
                                                                  const tl_enc_sample_t *e,
                                                                  const tick_faults_t *t, uint8_t *out)
{
    /* latch_faults, the e-stop input and the bridge input */
    uint16_t f = t->all | latch_bridge(i, t->safety);
    if (e->bridge_fault)
        f |= TLP_FAULT_BRIDGE;
    if (e->illegal != a->illegal_seen) {
        f |= TLP_FAULT_ENCODER;
        a->illegal_seen = e->illegal;
    }
    uint8_t lim = pv(a, TLP_P_LIMIT_SW) ? (uint8_t)(e->limits & (TLP_LIMIT_NEG | TLP_LIMIT_POS)) : 0u;
    a->limits = lim;
    if (lim) {
        lim &= (uint8_t)~home_switch(a);
        if (lim & TLP_LIMIT_NEG)
            f |= TLP_FAULT_LIMIT_NEG;
        if (lim & TLP_LIMIT_POS)
            f |= TLP_FAULT_LIMIT_POS;
    }
    if (!a->enabled)
        return f;
    f |= t->enabled;
    if ((t->safety & TL_HAL_SAFE_FORCED) && f == 0u)
        f |= TLP_FAULT_HW_SAFE;   /* forced off by a cause not seen above */
    if (t->link)
        f |= TLP_FAULT_LINK;
    /* following error |sp - pos| > FOLLOW_LIMIT, sp in counts (int32 range: it lies between
     * positions and targets), the difference in 33 bits */
    int32_t sp = (int32_t)(a->c.sp_q16 >> 16);
    uint32_t fl = (uint32_t)pv(a, TLP_P_FOLLOW_LIMIT);
    uint32_t ad = sp >= a->pos ? (uint32_t)sp - (uint32_t)a->pos : (uint32_t)a->pos - (uint32_t)sp;
    if (ad > fl)
        f |= TLP_FAULT_FOLLOWING;
    /* Outside the soft limits: a fault unless the axis was enabled out there
     * (it may then only come back in); back inside, that allowance ends. */
    uint8_t o = soft_side(a);
    *out = o;
    if (a->recover | o) {
        a->recover &= o;
        if (o & (uint8_t)~a->recover)
            f |= TLP_FAULT_SOFT_LIMIT;
    }
    return f | stall_check(a);
}

/* Sides toward which the axis must not be driven: a latched limit fault, a
 * limit switch open now, or soft, the soft-limit side the position is beyond. */
static inline __attribute__((always_inline)) uint8_t blocked_with(const tl_axis_t *a, uint8_t soft)
{
    return (uint8_t)(a->limits | soft | ((a->faults & TLP_FAULT_LIMIT_NEG) ? TLP_LIMIT_NEG : 0u) |
                     ((a->faults & TLP_FAULT_LIMIT_POS) ? TLP_LIMIT_POS : 0u));
}
static uint8_t blocked(const tl_axis_t *a) { return blocked_with(a, soft_side(a)); }
uint8_t tl_axis_blocked(const tl_axis_t *a) { return blocked(a); }

/* One period of homing (the phases above); the point found reads HOME_POS. */
static void home_tick(tl_axis_t *a, uint32_t i, uint32_t now)
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

/* One axis of the control iteration (inlined with a constant i). */
static inline __attribute__((always_inline)) void axis_tick(tl_servo_t *s, uint32_t i, const tick_faults_t *t)
{
    tl_axis_t *a = &s->ax[i];
    tl_enc_sample_t e;
    hal_enc_read_inline(i, &e);
    a->pos = wrap_add(e.pos, a->offset);
    if (a->drive)
        tl_ctl_hold(&a->c, a->pos);   /* open loop: the set-point follows, no following error */
    uint8_t out = 0;
    uint16_t f = axis_checks(a, i, &e, t, &out);
    if (f) {
        uint16_t fresh = f & (uint16_t)~a->faults;
        a->faults |= f;
        if (f & (TLP_FAULT_ENCODER | TLP_FAULT_RUNAWAY))
            a->home = TLP_HOME_STATE_NOT_HOMED;   /* the position is no longer trusted */
        if (a->enabled && fresh)
            disable_axis(s, i);
    }
    /* An old direction-blocking fault lets the axis be driven out; any other stops it. */
    if (a->enabled && (a->faults & (uint16_t)~TLP_FAULT_DIRECTIONAL))
        disable_axis(s, i);
    bool homing = a->home == TLP_HOME_STATE_HOMING;
    if (homing)
        home_tick(a, i, e.now);
    int32_t cmd = tl_ctl_step_inline(&a->c, &a->ctl, a->pos, e.edge_time, e.now, e.interval, a->enabled);
    if (a->drive)
        cmd = a->drive_duty;
    if (!a->enabled) {
        cmd = 0;
    } else {
        /* blocked(a): the soft-limit sides from the checks, unless homing moved the position */
        uint8_t b = homing ? blocked(a) : blocked_with(a, out);
        if (((b & TLP_LIMIT_NEG) && cmd < 0) || ((b & TLP_LIMIT_POS) && cmd > 0))
            cmd = 0;
    }
    a->cmd = cmd;
    hal_pwm_cmd(i, cmd);
}

void tl_servo_tick(tl_servo_t *s)
{
    tick_faults_t t;
    t.safety = hal_safety();
    s->ticks++;
    if (s->link_idle_ticks != 0xFFFFFFFFu)
        s->link_idle_ticks++;
    t.all = (t.safety & TL_HAL_SAFE_ESTOP_IN) ? TLP_FAULT_ESTOP : 0u;
    t.enabled = latch_enabled(t.safety);
    t.link = s->link_idle_ticks > s->link_timeout_ticks;
    _Static_assert(TL_AXES == 2, "the control iteration is written out for two axes");
    axis_tick(s, 0u, &t);
    axis_tick(s, 1u, &t);
    /* telem_phase = ticks mod telem_every, counted: no divide in the interrupt */
    if (s->telem_every && ++s->telem_phase >= s->telem_every) {
        s->telem_phase = 0;
        s->telem_due = true;
    }
}

/* ---- link ---------------------------------------------------------------- */

static void sat_inc(uint16_t *c)
{
    if (*c != 0xFFFFu)
        (*c)++;
}

TL_FOR_SIZE static void send(tl_servo_t *s, tl_tx_fn tx, uint16_t seq, uint8_t cmd, const uint8_t *p, uint8_t len)
{
    uint8_t wire[TLP_MAX_WIRE];
    uint32_t n = (uint32_t)tl_frame_encode(seq, cmd, p, len, wire, sizeof wire);
    if (n == 0u || !tx(wire, n))
        sat_inc(&s->cnt.tx_dropped);
}

TL_FOR_SIZE static void send_status(tl_servo_t *s, tl_tx_fn tx, uint16_t seq, uint8_t cmd, uint8_t st)
{
    send(s, tx, seq, cmd, &st, 1u);
}

static bool axis_mask_ok(uint8_t m) { return m != 0u && (m & ~((1u << TL_AXES) - 1u)) == 0u; }

TL_FOR_SIZE static uint8_t get_param(const tl_servo_t *s, uint8_t axis, uint8_t id, int32_t *out)
{
    int k = tl_param_index(id);
    if (k == IDX_NONE)
        return TLP_ST_BAD_ARG;
    if (TLP_PARAM_INFO[k].global) {
        if (axis != TLP_GLOBAL_AXIS)
            return TLP_ST_BAD_ARG;
        *out = s->g[k];
        return TLP_ST_OK;
    }
    if (axis >= TL_AXES)
        return TLP_ST_BAD_ARG;
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

/* Bounds between parameters and the tighten-only rule; TLP_ST_OK if v may be stored. */
static uint8_t param_allowed(const tl_servo_t *s, uint8_t axis, uint8_t id, int k, int32_t v)
{
    const tlp_param_info_t *info = &TLP_PARAM_INFO[k];
    if (v < info->min || v > info->max)
        return TLP_ST_RANGE;
    if (info->tighten && any_enabled(s)) {
        int32_t cur = info->global ? s->g[k] : s->ax[axis].p[k];
        if (info->tighten > 0 ? v < cur : v > cur)
            return TLP_ST_LOOSEN;
    }
    if (info->global) {
        if (id == TLP_P_PWM_MAX_HZ)
            for (uint32_t i = 0; i < TL_AXES; i++)
                if (!carrier_ok(s, pv(&s->ax[i], TLP_P_FDIV), v))
                    return TLP_ST_RANGE;
        return TLP_ST_OK;
    }
    const tl_axis_t *a = &s->ax[axis];
    int32_t tau = pv(a, TLP_P_TAU_MAX_MNM), cpr = pv(a, TLP_P_COUNTS_PER_REV);
    switch (id) {
    case TLP_P_SOFT_MIN: return v > pv(a, TLP_P_SOFT_MAX) ? TLP_ST_RANGE : TLP_ST_OK;
    case TLP_P_SOFT_MAX: return v < pv(a, TLP_P_SOFT_MIN) ? TLP_ST_RANGE : TLP_ST_OK;
    case TLP_P_PW0: return v > pv(a, TLP_P_PWMAX) ? TLP_ST_RANGE : TLP_ST_OK;
    case TLP_P_PWMAX: return v < pv(a, TLP_P_PW0) ? TLP_ST_RANGE : TLP_ST_OK;
    case TLP_P_FDIV: return carrier_ok(s, v, gv(s, TLP_P_PWM_MAX_HZ)) ? TLP_ST_OK : TLP_ST_RANGE;
    case TLP_P_KP_Q16:
    case TLP_P_KD_Q16:
    case TLP_P_KI_Q16: return v <= raw_gain_max(tau, cpr) ? TLP_ST_OK : TLP_ST_RANGE;
    case TLP_P_KP_UNM_RAD:
    case TLP_P_KD_UNMS_RAD:
    case TLP_P_KI_UNM_RADS: {
        /* a raw gain that saturated would read back as a smaller physical gain */
        int32_t raw = tl_gain_raw_from_phys(v, tau, cpr);
        return (raw == 0x7FFFFFFF && tl_gain_phys_from_raw(raw, tau, cpr) < v) ? TLP_ST_RANGE : TLP_ST_OK;
    }
    case TLP_P_TAU_MAX_MNM: return gains_fit(a, v, cpr) ? TLP_ST_OK : TLP_ST_RANGE;
    case TLP_P_COUNTS_PER_REV: return gains_fit(a, tau, v) ? TLP_ST_OK : TLP_ST_RANGE;
    default: return TLP_ST_OK;
    }
}

static uint8_t set_param(tl_servo_t *s, uint8_t axis, uint8_t id, int32_t v)
{
    int k = tl_param_index(id);
    if (k == IDX_NONE)
        return TLP_ST_BAD_ARG;
    const tlp_param_info_t *info = &TLP_PARAM_INFO[k];
    if ((info->global && axis != TLP_GLOBAL_AXIS) || (!info->global && axis >= TL_AXES))
        return TLP_ST_BAD_ARG;
    hal_irq_off();
    uint8_t st = param_allowed(s, axis, id, k, v);
    if (st != TLP_ST_OK) {
        hal_irq_on();
        return st;
    }
    /* The new value goes into copies of the parameters, and everything derived
     * from them is worked out with interrupts on (the conversions divide); one
     * short critical section then swaps it in, so a SET_PARAM delays the
     * control interrupt by a few copies, not by the arithmetic.  The check above
     * stays valid meanwhile: only commands enable an axis, and they run here. */
    hal_irq_on();
    axis_cfg_t cfg[TL_AXES];
    if (info->global) {
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
    } else {
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
        axis_cfg(p, (uint32_t)gv(s, TLP_P_PERIOD_US), s->clk_hz, &cfg[0]);
        hal_irq_off();
        a->p[slot] = value;
        commit_axis(s, axis, &cfg[0]);
        if (id == TLP_P_BRAKE && a->enabled)
            hal_pwm_enable(axis, true, v != 0);
    }
    hal_irq_on();
    return TLP_ST_OK;
}

static uint8_t do_enable(tl_servo_t *s, uint8_t mask, uint8_t on)
{
    if (!axis_mask_ok(mask) || on > 1u)
        return TLP_ST_BAD_ARG;
    hal_irq_off();
    if (!on) {
        for (uint32_t i = 0; i < TL_AXES; i++)
            if (mask & (1u << i))
                disable_axis(s, i);
        hal_irq_on();
        return TLP_ST_OK;
    }
    uint32_t latched = fold_latch(s);
    uint8_t st = TLP_ST_OK;
    for (uint32_t i = 0; i < TL_AXES; i++)
        if ((mask & (1u << i)) && (s->ax[i].faults & (uint16_t)~TLP_FAULT_DIRECTIONAL))
            st = TLP_ST_STATE;
    if (hal_safety() & TL_HAL_SAFE_ESTOP_IN)
        st = TLP_ST_STATE;
    if (st == TLP_ST_OK) {
        /* The SoC latch (the reset-time ESTOP, or causes now recorded as faults) is
         * acknowledged here and by CLEAR_FAULT only. */
        hal_safety_ack(latched);
        if (hal_safety() & TL_HAL_SAFE_FORCED)
            st = TLP_ST_STATE;
    }
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
        a->cmd = 0;
        a->enabled = true;
        hal_pwm_cmd(i, 0);
        hal_pwm_enable(i, true, pv(a, TLP_P_BRAKE) != 0);
    }
    s->link_idle_ticks = 0;
    hal_irq_on();
    return TLP_ST_OK;
}

static uint8_t do_clear(tl_servo_t *s, uint8_t mask)
{
    if (!axis_mask_ok(mask))
        return TLP_ST_BAD_ARG;
    bool left = false;
    hal_irq_off();
    uint32_t latched = fold_latch(s);
    uint32_t safety = hal_safety();
    for (uint32_t i = 0; i < TL_AXES; i++) {
        if (!(mask & (1u << i)))
            continue;
        tl_axis_t *a = &s->ax[i];
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
    return left ? TLP_ST_STATE : TLP_ST_OK;
}

static uint8_t do_move(tl_servo_t *s, uint8_t axis, uint8_t mode, int32_t target)
{
    if (axis >= TL_AXES || (mode & (uint8_t)~(TLP_MOVE_TRAPEZOID | TLP_MOVE_UNHOMED)))
        return TLP_ST_BAD_ARG;
    tl_axis_t *a = &s->ax[axis];
    if (!a->enabled || a->home == TLP_HOME_STATE_HOMING)
        return TLP_ST_STATE;
    if (a->home != TLP_HOME_STATE_HOMED && !(mode & TLP_MOVE_UNHOMED))
        return TLP_ST_NOT_HOMED;
    if (target < pv(a, TLP_P_SOFT_MIN) || target > pv(a, TLP_P_SOFT_MAX))
        return TLP_ST_RANGE;
    uint8_t b = blocked(a);
    if (((b & TLP_LIMIT_NEG) && target < a->pos) || ((b & TLP_LIMIT_POS) && target > a->pos))
        return TLP_ST_RANGE;
    int64_t d = (int64_t)target - a->pos;
    if (!(mode & TLP_MOVE_TRAPEZOID) && (d > pv(a, TLP_P_FOLLOW_LIMIT) || -d > pv(a, TLP_P_FOLLOW_LIMIT)))
        return TLP_ST_RANGE;   /* a step that far would trip the following error at once */
    hal_irq_off();
    a->drive = false;
    tl_ctl_move(&a->c, target, (mode & TLP_MOVE_TRAPEZOID) != 0u);
    hal_irq_on();
    return TLP_ST_OK;
}

static uint8_t do_home(tl_servo_t *s, uint8_t axis, uint8_t mode, uint8_t index)
{
    if (axis >= TL_AXES || mode > TLP_HOME_MODE_HERE || index > 1u)
        return TLP_ST_BAD_ARG;
    tl_axis_t *a = &s->ax[axis];
    if (a->home == TLP_HOME_STATE_HOMING)
        return TLP_ST_STATE;
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
        return TLP_ST_STATE;
    }
    a->drive = false;
    a->home = TLP_HOME_STATE_HOMING;
    a->home_phase = HOME_SEEK;
    a->home_dir = mode == TLP_HOME_MODE_NEG ? -1 : 1;
    a->home_index = index != 0u;
    a->home_sp_q16 = (int64_t)a->pos * 65536;
    tl_ctl_hold(&a->c, a->pos);
    hal_irq_on();
    return TLP_ST_OK;
}

TL_FOR_SIZE static void handle(tl_servo_t *s, const tl_frame_t *f, tl_tx_fn tx)
{
    uint8_t rc = f->cmd | TLP_REPLY_FLAG;
    uint8_t rep[TLP_MAX_PAYLOAD];
    uint8_t need, tag;
    switch (f->cmd) {
    case TLP_CMD_IDENTIFY: need = TLP_CMD_IDENTIFY_REQ_LEN; break;
    case TLP_CMD_GET_PARAM: need = TLP_CMD_GET_PARAM_REQ_LEN; break;
    case TLP_CMD_SET_PARAM: need = TLP_CMD_SET_PARAM_REQ_LEN; break;
    case TLP_CMD_ENABLE: need = TLP_CMD_ENABLE_REQ_LEN; break;
    case TLP_CMD_MOVE: need = TLP_CMD_MOVE_REQ_LEN; break;
    case TLP_CMD_STOP: need = TLP_CMD_STOP_REQ_LEN; break;
    case TLP_CMD_STATUS: need = TLP_CMD_STATUS_REQ_LEN; break;
    case TLP_CMD_TELEMETRY: need = TLP_CMD_TELEMETRY_REQ_LEN; break;
    case TLP_CMD_CLEAR_FAULT: need = TLP_CMD_CLEAR_FAULT_REQ_LEN; break;
    case TLP_CMD_BOOTLOADER: need = TLP_CMD_BOOTLOADER_REQ_LEN; break;
    case TLP_CMD_COUNTERS: need = TLP_CMD_COUNTERS_REQ_LEN; break;
    case TLP_CMD_HEARTBEAT: need = TLP_CMD_HEARTBEAT_REQ_LEN; break;
    case TLP_CMD_HOME: need = TLP_CMD_HOME_REQ_LEN; break;
    case TLP_CMD_SESSION: need = TLP_CMD_SESSION_REQ_LEN; break;
    case TLP_CMD_DRIVE: need = TLP_CMD_DRIVE_REQ_LEN; break;
    case TLP_CMD_SAVE: need = TLP_CMD_SAVE_REQ_LEN; break;
    default:
        sat_inc(&s->cnt.unknown);
        send_status(s, tx, f->seq, rc, TLP_ST_UNKNOWN_CMD);
        return;
    }
    tag = (f->len == need + TLP_AUTH_TAG_BYTES) ? TLP_AUTH_TAG_BYTES : 0u;   /* a MAC follows the payload */
    if (f->len != need + tag) {
        sat_inc(&s->cnt.length);
        send_status(s, tx, f->seq, rc, TLP_ST_LENGTH);
        return;
    }
    if (!tag && tlp_needs_key(f->cmd, f->payload)) {
        sat_inc(&s->cnt.auth);
        send_status(s, tx, f->seq, rc, tl_auth_missing(&s->auth));
        return;
    }
    bool seq_checked = f->cmd != TLP_CMD_IDENTIFY && f->cmd != TLP_CMD_SESSION;
    if (seq_checked && !tl_seq_is_new(&s->seq, f->seq)) {
        sat_inc(&s->cnt.replay);
        send_status(s, tx, f->seq, rc, TLP_ST_REPLAY);
        return;
    }
    if (tag) {
        uint8_t ast = tl_auth_verify(&s->auth, f);   /* outside the control interrupt: ~29 000 cycles */
        if (ast != TLP_ST_OK) {
            sat_inc(ast == TLP_ST_REPLAY ? &s->cnt.replay : &s->cnt.auth);
            send_status(s, tx, f->seq, rc, ast);
            return;
        }
    }
    if (seq_checked)
        tl_seq_accept(&s->seq, f->seq);
    sat_inc(&s->cnt.frames_ok);
    const uint8_t *q = f->payload;
    uint8_t st = TLP_ST_OK;
    uint8_t n = 1;
    switch (f->cmd) {
    case TLP_CMD_IDENTIFY:
        rep[TLP_IDENTIFY_REP_PROTO_VERSION] = TLP_VERSION;
        tl_put_u16(&rep[TLP_IDENTIFY_REP_FW_VERSION], TLP_FIRMWARE_VERSION);
        tl_put_u32(&rep[TLP_IDENTIFY_REP_BUILD_ID], hal_build_id());
        rep[TLP_IDENTIFY_REP_AXIS_COUNT] = TL_AXES;
        tl_put_u16(&rep[TLP_IDENTIFY_REP_LAST_SEQ], s->seq.last);
        tl_put_u32(&rep[TLP_IDENTIFY_REP_CLK_HZ], s->clk_hz);
        n = TLP_CMD_IDENTIFY_REP_LEN;
        break;
    case TLP_CMD_GET_PARAM: {
        int32_t v = 0;
        st = get_param(s, q[TLP_GET_PARAM_REQ_AXIS], q[TLP_GET_PARAM_REQ_PARAM], &v);
        tl_put_u32(&rep[TLP_GET_PARAM_REP_VALUE], (uint32_t)v);
        n = TLP_CMD_GET_PARAM_REP_LEN;
        break;
    }
    case TLP_CMD_SET_PARAM: {
        uint8_t axis = q[TLP_SET_PARAM_REQ_AXIS], id = q[TLP_SET_PARAM_REQ_PARAM];
        st = set_param(s, axis, id, (int32_t)tl_get_u32(&q[TLP_SET_PARAM_REQ_VALUE]));
        int32_t v = 0;
        if (st == TLP_ST_OK)
            (void)get_param(s, axis, id, &v);
        tl_put_u32(&rep[TLP_SET_PARAM_REP_VALUE], (uint32_t)v);
        n = TLP_CMD_SET_PARAM_REP_LEN;
        break;
    }
    case TLP_CMD_ENABLE:
        st = do_enable(s, q[TLP_ENABLE_REQ_MASK], q[TLP_ENABLE_REQ_ENABLE]);
        break;
    case TLP_CMD_MOVE:
        st = do_move(s, q[TLP_MOVE_REQ_AXIS], q[TLP_MOVE_REQ_MODE], (int32_t)tl_get_u32(&q[TLP_MOVE_REQ_TARGET]));
        break;
    case TLP_CMD_STOP: {
        uint8_t m = q[TLP_STOP_REQ_MASK];
        if (!axis_mask_ok(m)) {
            st = TLP_ST_BAD_ARG;
            break;
        }
        hal_irq_off();
        for (uint32_t i = 0; i < TL_AXES; i++)
            if (m & (1u << i)) {
                if (s->ax[i].home == TLP_HOME_STATE_HOMING)
                    s->ax[i].home = TLP_HOME_STATE_NOT_HOMED;
                s->ax[i].drive = false;
                tl_ctl_hold(&s->ax[i].c, s->ax[i].pos);
            }
        hal_irq_on();
        break;
    }
    case TLP_CMD_HEARTBEAT:
        break;
    case TLP_CMD_HOME:
        st = do_home(s, q[TLP_HOME_REQ_AXIS], q[TLP_HOME_REQ_MODE], q[TLP_HOME_REQ_INDEX]);
        break;
    case TLP_CMD_DRIVE:
        st = tl_drive_start(s, q[TLP_DRIVE_REQ_AXIS], (int16_t)tl_get_u16(&q[TLP_DRIVE_REQ_DUTY]));
        break;
    case TLP_CMD_SAVE:
        st = tl_store_command(s, q[TLP_SAVE_REQ_OP], rep);
        n = TLP_CMD_SAVE_REP_LEN;
        break;
    case TLP_CMD_STATUS: {
        uint8_t axis = q[TLP_STATUS_REQ_AXIS];
        if (axis >= TL_AXES) {
            st = TLP_ST_BAD_ARG;
            break;
        }
        const tl_axis_t *a = &s->ax[axis];
        rep[TLP_STATUS_REP_ENABLED] = a->enabled;
        tl_put_u16(&rep[TLP_STATUS_REP_FAULTS], a->faults);
        rep[TLP_STATUS_REP_MOVING] = a->c.moving || a->home == TLP_HOME_STATE_HOMING;
        rep[TLP_STATUS_REP_HOME] = a->home;
        rep[TLP_STATUS_REP_LIMITS] = a->limits;
        tl_put_u32(&rep[TLP_STATUS_REP_POSITION], (uint32_t)a->pos);
        tl_put_u32(&rep[TLP_STATUS_REP_SETPOINT], (uint32_t)(int32_t)(a->c.sp_q16 >> 16));
        tl_put_u32(&rep[TLP_STATUS_REP_VELOCITY_Q8], (uint32_t)a->c.vel_q8);
        tl_put_u16(&rep[TLP_STATUS_REP_PWM_CMD], (uint16_t)(int16_t)a->cmd);
        tl_put_u16(&rep[TLP_STATUS_REP_SAFETY], (uint16_t)hal_safety());
        uint32_t errs = (uint32_t)s->cnt.crc + s->cnt.framing + s->cnt.length + s->cnt.oversize;
        tl_put_u16(&rep[TLP_STATUS_REP_RX_ERRORS], (uint16_t)(errs > 0xFFFFu ? 0xFFFFu : errs));
        tl_put_u32(&rep[TLP_STATUS_REP_LOOP_CYCLES_MAX], s->loop_cycles_max);
        tl_put_u32(&rep[TLP_STATUS_REP_JITTER_CYCLES_MAX], s->jitter_cycles_max);
        n = TLP_CMD_STATUS_REP_LEN;
        break;
    }
    case TLP_CMD_TELEMETRY:
        hal_irq_off();
        s->telem_every = tl_get_u16(&q[TLP_TELEMETRY_REQ_EVERY]);
        s->telem_phase = s->telem_every ? (uint16_t)(s->ticks % s->telem_every) : 0u;
        hal_irq_on();
        break;
    case TLP_CMD_CLEAR_FAULT:
        st = do_clear(s, q[TLP_CLEAR_FAULT_REQ_MASK]);
        tl_put_u16(&rep[TLP_CLEAR_FAULT_REP_FAULTS0], s->ax[0].faults);
        tl_put_u16(&rep[TLP_CLEAR_FAULT_REP_FAULTS1], s->ax[1].faults);
        n = TLP_CMD_CLEAR_FAULT_REP_LEN;
        break;
    case TLP_CMD_BOOTLOADER:
        if (tl_get_u32(&q[TLP_BOOTLOADER_REQ_MAGIC]) != TLP_BOOTLOADER_MAGIC) {
            st = TLP_ST_BAD_ARG;
            break;
        }
        hal_irq_off();
        for (uint32_t i = 0; i < TL_AXES; i++)
            disable_axis(s, i);
        hal_irq_on();
        s->bootloader_req = true;
        break;
    case TLP_CMD_SESSION:
        st = tl_auth_session(&s->auth, &q[TLP_SESSION_REQ_HOST_NONCE], hal_cycles(), &rep[TLP_SESSION_REP_BOARD_NONCE],
                             &rep[TLP_SESSION_REP_PROOF]);
        n = TLP_CMD_SESSION_REP_LEN;
        break;
    case TLP_CMD_COUNTERS: {
        const uint16_t vals[10] = {s->cnt.frames_ok, s->cnt.crc, s->cnt.framing, s->cnt.length, s->cnt.oversize,
                                   s->cnt.unknown, s->cnt.replay, s->cnt.rejected, s->cnt.tx_dropped, s->cnt.auth};
        for (uint32_t k = 0; k < 10u; k++)
            tl_put_u16(&rep[TLP_COUNTERS_REP_FRAMES_OK + 2u * k], vals[k]);
        n = TLP_CMD_COUNTERS_REP_LEN;
        break;
    }
    default:
        break;
    }
    if (st != TLP_ST_OK) {
        sat_inc(&s->cnt.rejected);
        n = 1;
    } else if (tag && f->cmd < 32u && ((TLP_LINK_FEED_MASK >> f->cmd) & 1u)) {
        /* The host is in control: only a command that carried a verified MAC
         * feeds the watchdog (read-only commands never do, nor a STOP sent
         * without the key, which would otherwise keep an axis enabled for
         * anyone on the network). */
        s->link_idle_ticks = 0;
    }
    rep[0] = st;
    send(s, tx, f->seq, rc, rep, n);
}

TL_FOR_SIZE void tl_servo_rx_byte(tl_servo_t *s, uint8_t byte, tl_tx_fn tx)
{
    tl_frame_t f;
    uint8_t st = 0;
    tl_auth_stir(&s->auth, hal_cycles());
    switch (tl_rx_byte(&s->rx, byte, &f, &st)) {
    case TL_RX_FRAME:
        handle(s, &f, tx);
        break;
    case TL_RX_ERROR:
        switch (st) {
        case TLP_ST_CRC: sat_inc(&s->cnt.crc); break;
        case TLP_ST_LENGTH: sat_inc(&s->cnt.length); break;
        case TLP_ST_OVERSIZE: sat_inc(&s->cnt.oversize); break;
        default: sat_inc(&s->cnt.framing); break;
        }
        send_status(s, tx, 0u, TLP_ERROR_CMD, st);
        break;
    default:
        break;
    }
}

void tl_servo_telemetry(const tl_servo_t *s, uint8_t *p)
{
    tl_put_u32(&p[TLP_TELEM_TIME_US], (uint32_t)((uint64_t)s->ticks * (uint32_t)gv(s, TLP_P_PERIOD_US)));
    for (uint32_t i = 0; i < TL_AXES; i++) {
        const tl_axis_t *a = &s->ax[i];
        uint8_t *r = &p[TLP_TELEM_HEAD_LEN + i * TLP_TELEM_AX_LEN];
        tl_put_u32(&r[TLP_TELEM_AX_SETPOINT], (uint32_t)(int32_t)(a->c.sp_q16 >> 16));
        tl_put_u32(&r[TLP_TELEM_AX_POSITION], (uint32_t)a->pos);
        tl_put_u32(&r[TLP_TELEM_AX_VELOCITY_Q8], (uint32_t)a->c.vel_q8);
        tl_put_u32(&r[TLP_TELEM_AX_ERROR], (uint32_t)a->c.err_counts);
        tl_put_u16(&r[TLP_TELEM_AX_PWM_CMD], (uint16_t)(int16_t)a->cmd);
        tl_put_u16(&r[TLP_TELEM_AX_FAULTS], a->faults);
        r[TLP_TELEM_AX_ENABLED] = a->enabled;
    }
}
