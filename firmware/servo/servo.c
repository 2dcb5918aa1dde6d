/* SPDX-License-Identifier: MIT */
/* The servo core's start-up and its control iteration (servo.h): every period
 * tl_servo_tick reads both encoders, makes the safety checks of safety.h, runs
 * homing (homing.c) and the control law (control_step.h) and writes the PWM
 * commands; it is the hot path, with a cycle budget (docs/firmware.md,
 * "Timing").  Parameters are params.c, the fault latch safety.c and the link's
 * commands commands.c. */
#include "control_step.h"
#include "safety.h"
#include "store.h"

TL_FOR_SIZE void tl_servo_init(tl_servo_t *s)
{
    s->clk_hz = hal_clk_hz();
    tl_params_defaults(s);
    tl_rx_init(&s->rx);
    s->seq.any = false;
    s->seq.last = 0;
    s->cnt = (tl_counters_t){0};
    s->ticks = 0;
    s->link_idle_ticks = 0;
    s->telem_every = 0;
    s->telem_next = 0;
    s->telem_seq = 0;
    s->bootloader_req = false;
    s->baud_div_pending = 0;
    s->loop_cycles_max = 0;
    s->jitter_cycles_max = 0;
    s->overruns = 0;
    for (uint32_t i = 0; i < TL_AXES; i++) {
        tl_axis_t *a = &s->ax[i];
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
        enc_check_reset(a);
        a->drive = false;
        a->drive_duty = 0;
        tl_ctl_reset(&a->c, e.pos, e.now);
    }
    tl_store_load(s);   /* the saved parameters over the defaults (store.c) */
    tl_params_sync(s);
    for (uint32_t i = 0; i < TL_AXES; i++)
        tl_axis_disable(s, i);
    hal_set_baud_div((uint32_t)gv(s, TLP_P_BAUD_DIV));
    /* The key last: its HMAC states cost ~55 000 cycles, and the link rate is set before them. */
    tl_auth_init(&s->auth, hal_key_slot());
}

uint32_t tl_servo_period_cycles(const tl_servo_t *s) { return s->period_cycles; }


/* Faults f found by the checks: latched; the axis stops.  Out of line: the iteration
 * (both axes written out in one function) keeps one call where the whole response was,
 * so fewer of its branches jump beyond a conditional branch's 4 KiB reach (a branch
 * over a jump: 3 cycles more on tl_cpu_pipe, docs/firmware.md "Timing"). */
static __attribute__((noinline, cold)) void axis_fault(tl_servo_t *s, uint32_t i, uint16_t f)
{
    tl_axis_t *a = &s->ax[i];
    uint16_t fresh = f & (uint16_t)~a->faults;
    a->faults |= f;
    if (f & (TLP_FAULT_ENCODER | TLP_FAULT_RUNAWAY))
        a->home = TLP_HOME_STATE_NOT_HOMED;   /* the position is no longer trusted */
    if (a->enabled && fresh)
        tl_axis_disable(s, i);
}

/* One axis of the control iteration (inlined with a constant i). */
static inline __attribute__((always_inline)) void axis_tick(tl_servo_t *s, uint32_t i, const tick_faults_t *t)
{
    tl_axis_t *a = &s->ax[i];
    tl_enc_sample_t e;
    hal_enc_read_inline(i, &e);
    a->pos = wrap_add(e.pos, a->offset);
    /* drive and enabled read once into locals: the byte stores between would make the compiler
     * load them again (a char may alias anything).  Only tl_axis_disable clears drive in here,
     * and it clears enabled too, whose command is then 0 either way. */
    bool drive = a->drive;
    if (TL_UNLIKELY(drive))
        tl_ctl_hold(&a->c, a->pos);   /* open loop: the set-point follows, no following error */
    uint8_t out = 0;
    uint16_t f = axis_checks(a, i, &e, t, &out);
    if (TL_UNLIKELY(f))
        axis_fault(s, i, f);
    /* An old direction-blocking fault lets the axis be driven out; any other stops it. */
    uint16_t faults = a->faults;   /* read once: the disabling below and homing change none */
    if (TL_UNLIKELY((faults & (uint16_t)~TLP_FAULT_DIRECTIONAL) && a->enabled))
        tl_axis_disable(s, i);
    bool enabled = a->enabled;   /* after the last change here (homing changes none) */
    bool homing = a->home == TLP_HOME_STATE_HOMING;
    if (__builtin_expect(homing, 0))   /* homing.c, a call: keep the path of an axis under control straight */
        tl_home_tick(a, i, e.now);
    int32_t cmd = tl_ctl_step_inline(&a->c, &a->ctl, a->pos, e.edge_time, e.now, e.interval, enabled);
    if (TL_UNLIKELY(drive))
        cmd = a->drive_duty;
    if (TL_UNLIKELY(!enabled)) {
        cmd = 0;
    } else {
        /* blocked(a): the soft-limit sides from the checks, unless homing moved the position */
        uint8_t b = blocked_with(a, faults, homing ? soft_side(a) : out);
        if (TL_UNLIKELY(((b & TLP_LIMIT_NEG) && cmd < 0) || ((b & TLP_LIMIT_POS) && cmd > 0)))
            cmd = 0;
    }
    a->cmd = cmd;
    hal_pwm_cmd(i, cmd);
}

TL_HOT_LAYOUT void tl_servo_tick(tl_servo_t *s)
{
    tick_faults_t t;
    t.safety = hal_safety();
    s->ticks++;
    if (s->link_idle_ticks != 0xFFFFFFFFu)
        s->link_idle_ticks++;
    t.all = (t.safety & TL_HAL_SAFE_ESTOP_IN) ? TLP_FAULT_ESTOP : 0u;
    t.enabled = latch_enabled(t.safety);
    t.link = s->link_idle_ticks > s->link_timeout_ticks;
    t.ticks = s->ticks;
    t.odd = s->runaway_odd;
    _Static_assert(TL_AXES == 2, "the control iteration is written out for two axes");
    axis_tick(s, 0u, &t);
    axis_tick(s, 1u, &t);
}

bool tl_servo_telemetry_due(tl_servo_t *s)
{
    uint32_t every = s->telem_every, ticks = s->ticks;   /* one read of the interrupt's count */
    if (every == 0u || (int32_t)(ticks - s->telem_next) < 0)
        return false;
    do
        s->telem_next += every;
    while ((int32_t)(ticks - s->telem_next) >= 0);
    return true;
}

void tl_servo_stream_telemetry(tl_servo_t *s, tl_tx_fn tx)
{
    if (!tl_servo_telemetry_due(s))
        return;
    uint8_t p[TLP_TELEM_LEN];
    uint8_t wire[TLP_MAX_WIRE];
    hal_irq_off();   /* one period's values, not two */
    tl_servo_telemetry(s, p);
    hal_irq_on();
    uint32_t n = (uint32_t)tl_frame_encode(s->telem_seq++, TLP_TELEMETRY_CMD, p, TLP_TELEM_LEN, wire, sizeof wire);
    if (!tx(wire, n) && s->cnt.tx_dropped != 0xFFFFu)
        s->cnt.tx_dropped++;
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
