/* SPDX-License-Identifier: MIT */
/* Servo application core (servo.h): parameters, safety and the command
 * handler.  The safety rules (docs/firmware.md, "Safety"):
 *  - power-up: both axes disabled; the SoC's reset-time ESTOP latch bit is
 *    acknowledged only by an ENABLE command;
 *  - e-stop, bridge fault, illegal encoder transitions, following error, soft
 *    limits, link silence and a hardware-forced safe state each disable the
 *    axis in the same control period and latch a fault bit; only CLEAR_FAULT
 *    (when the cause is gone) clears it, and the axis then stays disabled
 *    until ENABLE;
 *  - a frame that fails any check, or a replayed one, is counted and answered
 *    with an error and changes nothing. */
#include "servo.h"

#include "hal.h"

#define IDX_NONE (-1)

/* id -> index into TLP_PARAM_INFO, built once: the control iteration reads
 * parameters by id, and a search per read cost ~1000 cycles per iteration. */
static int8_t param_idx[256];
static bool param_idx_ready;

int tl_param_index(uint8_t id)
{
    if (!param_idx_ready) {
        for (int i = 0; i < 256; i++)
            param_idx[i] = IDX_NONE;
        for (int i = 0; i < (int)TLP_PARAM_COUNT; i++)
            param_idx[TLP_PARAM_INFO[i].id] = (int8_t)i;
        param_idx_ready = true;
    }
    return param_idx[id];
}

static int32_t pv(const tl_axis_t *a, uint8_t id) { return a->p[tl_param_index(id)]; }
static int32_t gv(const tl_servo_t *s, uint8_t id) { return s->g[tl_param_index(id)]; }

static void sync_axis(tl_servo_t *s, uint32_t i)
{
    tl_axis_t *a = &s->ax[i];
    a->ctl.law = (uint32_t)pv(a, TLP_P_LAW);
    a->ctl.kp_q16 = pv(a, TLP_P_KP_Q16);
    a->ctl.kd_q16 = pv(a, TLP_P_KD_Q16);
    a->ctl.ki_q16 = pv(a, TLP_P_KI_Q16);
    a->ctl.deadband_q16 = pv(a, TLP_P_DEADBAND_Q16);
    a->ctl.cmd_limit = pv(a, TLP_P_CMD_LIMIT);
    a->ctl.vel_mode = (uint32_t)pv(a, TLP_P_VEL_MODE);
    a->ctl.vmax_cps = pv(a, TLP_P_VMAX);
    a->ctl.amax_cps2 = pv(a, TLP_P_AMAX);
    tl_ctl_derive(&a->c, &a->ctl, (uint32_t)gv(s, TLP_P_PERIOD_US), s->clk_hz);
    s->period_cycles = (uint32_t)((uint64_t)(uint32_t)gv(s, TLP_P_PERIOD_US) * s->clk_hz / 1000000u);
    s->link_timeout_ticks = (uint32_t)gv(s, TLP_P_LINK_TIMEOUT_MS) * 1000u / (uint32_t)gv(s, TLP_P_PERIOD_US);
    if (s->link_timeout_ticks == 0u)
        s->link_timeout_ticks = 1u;
    hal_pwm_config(i, (uint32_t)pv(a, TLP_P_FDIV), (uint32_t)pv(a, TLP_P_PW0), (uint32_t)pv(a, TLP_P_PWMAX));
}

static void disable_axis(tl_servo_t *s, uint32_t i)
{
    tl_axis_t *a = &s->ax[i];
    hal_pwm_enable(i, false, pv(a, TLP_P_BRAKE) != 0);
    hal_pwm_cmd(i, 0);
    a->enabled = false;
    tl_ctl_hold(&a->c, a->pos);
    a->c.cmd = 0;
}

void tl_servo_init(tl_servo_t *s)
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
        a->illegal_seen = e.illegal;
        a->faults = 0;
        tl_ctl_reset(&a->c, e.pos, e.now);
        sync_axis(s, i);
        disable_axis(s, i);
    }
    hal_set_baud_div((uint32_t)gv(s, TLP_P_BAUD_DIV));
}

uint32_t tl_servo_period_cycles(const tl_servo_t *s) { return s->period_cycles; }


void tl_servo_tick(tl_servo_t *s)
{
    uint32_t safety = hal_safety();
    uint32_t timeout = s->link_timeout_ticks;
    s->ticks++;
    if (s->link_idle_ticks != 0xFFFFFFFFu)
        s->link_idle_ticks++;
    for (uint32_t i = 0; i < TL_AXES; i++) {
        tl_axis_t *a = &s->ax[i];
        tl_enc_sample_t e;
        hal_enc_read(i, &e);
        a->pos = e.pos;
        uint8_t f = 0;
        if (safety & TL_HAL_SAFE_ESTOP_IN)
            f |= TLP_FAULT_ESTOP;
        if (e.bridge_fault)
            f |= TLP_FAULT_BRIDGE;
        if (e.illegal != a->illegal_seen) {
            f |= TLP_FAULT_ENCODER;
            a->illegal_seen = e.illegal;
        }
        if (a->enabled) {
            if (safety & TL_HAL_SAFE_ESTOP)
                f |= TLP_FAULT_ESTOP;
            if (safety & (i == 0u ? TL_HAL_SAFE_FAULT0 : TL_HAL_SAFE_FAULT1))
                f |= TLP_FAULT_BRIDGE;
            if ((safety & TL_HAL_SAFE_WDOG) || ((safety & TL_HAL_SAFE_FORCED) && f == 0u))
                f |= TLP_FAULT_HW_SAFE;
            if (s->link_idle_ticks > timeout)
                f |= TLP_FAULT_LINK;
            int64_t ferr = (a->c.sp_q16 >> 16) - (int64_t)e.pos;
            if (ferr > pv(a, TLP_P_FOLLOW_LIMIT) || -ferr > pv(a, TLP_P_FOLLOW_LIMIT))
                f |= TLP_FAULT_FOLLOWING;
            if (e.pos < pv(a, TLP_P_SOFT_MIN) || e.pos > pv(a, TLP_P_SOFT_MAX))
                f |= TLP_FAULT_SOFT_LIMIT;
        }
        a->faults |= f;
        if (a->enabled && a->faults)
            disable_axis(s, i);
        int32_t cmd = tl_ctl_step(&a->c, &a->ctl, e.pos, e.edge_time, e.now, e.interval, a->enabled);
        hal_pwm_cmd(i, a->enabled ? cmd : 0);
    }
    if (s->telem_every && (s->ticks % s->telem_every) == 0u)
        s->telem_due = true;
}

/* ---- link ---------------------------------------------------------------- */

static void sat_inc(uint16_t *c)
{
    if (*c != 0xFFFFu)
        (*c)++;
}

static void send(tl_servo_t *s, tl_tx_fn tx, uint16_t seq, uint8_t cmd, const uint8_t *p, uint8_t len)
{
    uint8_t wire[TLP_MAX_WIRE];
    uint32_t n = (uint32_t)tl_frame_encode(seq, cmd, p, len, wire, sizeof wire);
    if (n == 0u || !tx(wire, n))
        sat_inc(&s->cnt.tx_dropped);
}

static void send_status(tl_servo_t *s, tl_tx_fn tx, uint16_t seq, uint8_t cmd, uint8_t st)
{
    send(s, tx, seq, cmd, &st, 1u);
}

static bool axis_mask_ok(uint8_t m) { return m != 0u && (m & ~((1u << TL_AXES) - 1u)) == 0u; }

static uint8_t get_param(const tl_servo_t *s, uint8_t axis, uint8_t id, int32_t *out)
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

static uint8_t set_param(tl_servo_t *s, uint8_t axis, uint8_t id, int32_t v)
{
    int k = tl_param_index(id);
    if (k == IDX_NONE)
        return TLP_ST_BAD_ARG;
    const tlp_param_info_t *info = &TLP_PARAM_INFO[k];
    if ((info->global && axis != TLP_GLOBAL_AXIS) || (!info->global && axis >= TL_AXES))
        return TLP_ST_BAD_ARG;
    if (v < info->min || v > info->max)
        return TLP_ST_RANGE;
    if (id == TLP_P_SOFT_MIN && v > pv(&s->ax[axis], TLP_P_SOFT_MAX))
        return TLP_ST_RANGE;
    if (id == TLP_P_SOFT_MAX && v < pv(&s->ax[axis], TLP_P_SOFT_MIN))
        return TLP_ST_RANGE;
    hal_irq_off();
    if (info->global) {
        if (id == TLP_P_BAUD_DIV)
            s->baud_div_pending = (uint32_t)v;
        s->g[k] = v;
        for (uint32_t i = 0; i < TL_AXES; i++)
            sync_axis(s, i);
    } else {
        tl_axis_t *a = &s->ax[axis];
        int32_t tau = pv(a, TLP_P_TAU_MAX_MNM), cpr = pv(a, TLP_P_COUNTS_PER_REV);
        switch (id) {
        case TLP_P_KP_UNM_RAD: a->p[tl_param_index(TLP_P_KP_Q16)] = tl_gain_raw_from_phys(v, tau, cpr); break;
        case TLP_P_KD_UNMS_RAD: a->p[tl_param_index(TLP_P_KD_Q16)] = tl_gain_raw_from_phys(v, tau, cpr); break;
        case TLP_P_KI_UNM_RADS: a->p[tl_param_index(TLP_P_KI_Q16)] = tl_gain_raw_from_phys(v, tau, cpr); break;
        default: a->p[k] = v; break;
        }
        sync_axis(s, axis);
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
    if (!on) {
        hal_irq_off();
        for (uint32_t i = 0; i < TL_AXES; i++)
            if (mask & (1u << i))
                disable_axis(s, i);
        hal_irq_on();
        return TLP_ST_OK;
    }
    for (uint32_t i = 0; i < TL_AXES; i++)
        if ((mask & (1u << i)) && s->ax[i].faults)
            return TLP_ST_STATE;
    if (hal_safety() & TL_HAL_SAFE_ESTOP_IN)
        return TLP_ST_STATE;
    /* The SoC latch (reset-time ESTOP, or a cause that has gone) is acknowledged here and only here. */
    hal_safety_ack(TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG);
    if (hal_safety() & TL_HAL_SAFE_FORCED)
        return TLP_ST_STATE;
    hal_irq_off();
    for (uint32_t i = 0; i < TL_AXES; i++) {
        if (!(mask & (1u << i)) || s->ax[i].enabled)
            continue;
        tl_axis_t *a = &s->ax[i];
        tl_enc_sample_t e;
        hal_enc_read(i, &e);
        a->pos = e.pos;
        tl_ctl_reset(&a->c, e.pos, e.now);   /* set-point = where it is: no jump */
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
    uint32_t safety = hal_safety();
    bool left = false;
    hal_irq_off();
    for (uint32_t i = 0; i < TL_AXES; i++) {
        if (!(mask & (1u << i)))
            continue;
        tl_axis_t *a = &s->ax[i];
        tl_enc_sample_t e;
        hal_enc_read(i, &e);
        uint8_t keep = 0;
        if (safety & TL_HAL_SAFE_ESTOP_IN)
            keep |= TLP_FAULT_ESTOP;
        if (e.bridge_fault)
            keep |= TLP_FAULT_BRIDGE;
        if (a->faults & TLP_FAULT_ENCODER) {
            hal_enc_clear_illegal(i);
            a->illegal_seen = 0;
        }
        a->faults &= keep;
        left = left || a->faults;
    }
    hal_irq_on();
    if (!(safety & TL_HAL_SAFE_ESTOP_IN))
        hal_safety_ack(TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FAULT0 | TL_HAL_SAFE_FAULT1 | TL_HAL_SAFE_WDOG);
    return left ? TLP_ST_STATE : TLP_ST_OK;
}

static void handle(tl_servo_t *s, const tl_frame_t *f, tl_tx_fn tx)
{
    uint8_t rc = f->cmd | TLP_REPLY_FLAG;
    uint8_t rep[TLP_MAX_PAYLOAD];
    uint8_t need;
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
    default:
        sat_inc(&s->cnt.unknown);
        send_status(s, tx, f->seq, rc, TLP_ST_UNKNOWN_CMD);
        return;
    }
    if (f->len != need) {
        sat_inc(&s->cnt.length);
        send_status(s, tx, f->seq, rc, TLP_ST_LENGTH);
        return;
    }
    if (f->cmd != TLP_CMD_IDENTIFY) {
        if (!tl_seq_is_new(&s->seq, f->seq)) {
            sat_inc(&s->cnt.replay);
            send_status(s, tx, f->seq, rc, TLP_ST_REPLAY);
            return;
        }
        tl_seq_accept(&s->seq, f->seq);
    }
    sat_inc(&s->cnt.frames_ok);
    s->link_idle_ticks = 0;
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
    case TLP_CMD_MOVE: {
        uint8_t axis = q[TLP_MOVE_REQ_AXIS], mode = q[TLP_MOVE_REQ_MODE];
        int32_t target = (int32_t)tl_get_u32(&q[TLP_MOVE_REQ_TARGET]);
        if (axis >= TL_AXES || mode > 1u)
            st = TLP_ST_BAD_ARG;
        else if (!s->ax[axis].enabled)
            st = TLP_ST_STATE;
        else if (target < pv(&s->ax[axis], TLP_P_SOFT_MIN) || target > pv(&s->ax[axis], TLP_P_SOFT_MAX))
            st = TLP_ST_RANGE;
        else {
            hal_irq_off();
            tl_ctl_move(&s->ax[axis].c, target, mode == 1u);
            hal_irq_on();
        }
        break;
    }
    case TLP_CMD_STOP: {
        uint8_t m = q[TLP_STOP_REQ_MASK];
        if (!axis_mask_ok(m)) {
            st = TLP_ST_BAD_ARG;
            break;
        }
        hal_irq_off();
        for (uint32_t i = 0; i < TL_AXES; i++)
            if (m & (1u << i))
                tl_ctl_hold(&s->ax[i].c, s->ax[i].pos);
        hal_irq_on();
        break;
    }
    case TLP_CMD_STATUS: {
        uint8_t axis = q[TLP_STATUS_REQ_AXIS];
        if (axis >= TL_AXES) {
            st = TLP_ST_BAD_ARG;
            break;
        }
        const tl_axis_t *a = &s->ax[axis];
        rep[TLP_STATUS_REP_ENABLED] = a->enabled;
        rep[TLP_STATUS_REP_FAULTS] = a->faults;
        rep[TLP_STATUS_REP_MOVING] = a->c.moving;
        tl_put_u32(&rep[TLP_STATUS_REP_POSITION], (uint32_t)a->pos);
        tl_put_u32(&rep[TLP_STATUS_REP_SETPOINT], (uint32_t)(int32_t)(a->c.sp_q16 >> 16));
        tl_put_u32(&rep[TLP_STATUS_REP_VELOCITY_Q8], (uint32_t)a->c.vel_q8);
        tl_put_u16(&rep[TLP_STATUS_REP_PWM_CMD], (uint16_t)(int16_t)a->c.cmd);
        tl_put_u16(&rep[TLP_STATUS_REP_SAFETY], (uint16_t)hal_safety());
        uint32_t errs = (uint32_t)s->cnt.crc + s->cnt.framing + s->cnt.length + s->cnt.oversize;
        tl_put_u16(&rep[TLP_STATUS_REP_RX_ERRORS], (uint16_t)(errs > 0xFFFFu ? 0xFFFFu : errs));
        tl_put_u32(&rep[TLP_STATUS_REP_LOOP_CYCLES_MAX], s->loop_cycles_max);
        tl_put_u32(&rep[TLP_STATUS_REP_JITTER_CYCLES_MAX], s->jitter_cycles_max);
        n = TLP_CMD_STATUS_REP_LEN;
        break;
    }
    case TLP_CMD_TELEMETRY:
        s->telem_every = tl_get_u16(&q[TLP_TELEMETRY_REQ_EVERY]);
        break;
    case TLP_CMD_CLEAR_FAULT:
        st = do_clear(s, q[TLP_CLEAR_FAULT_REQ_MASK]);
        rep[TLP_CLEAR_FAULT_REP_FAULTS0] = s->ax[0].faults;
        rep[TLP_CLEAR_FAULT_REP_FAULTS1] = s->ax[1].faults;
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
    case TLP_CMD_COUNTERS: {
        const uint16_t vals[9] = {s->cnt.frames_ok, s->cnt.crc, s->cnt.framing, s->cnt.length, s->cnt.oversize,
                                  s->cnt.unknown, s->cnt.replay, s->cnt.rejected, s->cnt.tx_dropped};
        for (uint32_t k = 0; k < 9u; k++)
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
    }
    rep[0] = st;
    send(s, tx, f->seq, rc, rep, n);
}

void tl_servo_rx_byte(tl_servo_t *s, uint8_t byte, tl_tx_fn tx)
{
    tl_frame_t f;
    uint8_t st = 0;
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
        tl_put_u16(&r[TLP_TELEM_AX_PWM_CMD], (uint16_t)(int16_t)a->c.cmd);
        r[TLP_TELEM_AX_FAULTS] = a->faults;
        r[TLP_TELEM_AX_ENABLED] = a->enabled;
    }
}
