/* SPDX-License-Identifier: MIT */
/* Host unit tests of the firmware's plain C: link layer, control law,
 * trapezoid profile and the servo core's safety and command handling (on the
 * fake HAL).  Run by tests/test_firmware_host.py.
 *
 *   host_tests unit [seed]   run every test; prints the seed and the counts
 *   host_tests ctl           line-driven control.c, compared with
 *                            torqueloop/models/servo.py by the Python test */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "control.h"
#include "hal_fake.h"
#include "servo.h"
#include "tl_link.h"

static unsigned checks, failures;
#define CHECK(cond, ...)                                                         \
    do {                                                                         \
        checks++;                                                                \
        if (!(cond)) {                                                           \
            failures++;                                                          \
            fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                        \
            fputc('\n', stderr);                                                 \
        }                                                                        \
    } while (0)

static uint64_t rng_state;
static uint32_t rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint32_t)(rng_state >> 11);
}

/* ---- link ---------------------------------------------------------------- */

static void test_link(void)
{
    const uint8_t check_str[] = "123456789";
    CHECK(tl_crc16(check_str, 9, 0xFFFFu) == 0x29B1u, "CRC-16/CCITT-FALSE check value");
    for (int n = 0; n < 2000; n++) {
        uint8_t a[300], enc[310], dec[300];
        size_t len = rnd() % 300;
        for (size_t i = 0; i < len; i++)
            a[i] = (rnd() % 4 == 0) ? 0 : (uint8_t)rnd();
        size_t el = tl_cobs_encode(a, len, enc);
        CHECK(el <= len + len / 254 + 1, "COBS overhead %zu for %zu", el, len);
        CHECK(memchr(enc, 0, el) == NULL, "COBS output has a zero");
        int32_t dl = tl_cobs_decode(enc, el, dec, sizeof dec);
        CHECK(dl == (int32_t)len && memcmp(a, dec, len) == 0, "COBS round trip len %zu", len);
    }
    /* every frame round-trips, and every single-bit flip of it is rejected */
    for (int n = 0; n < 300; n++) {
        uint8_t payload[TLP_MAX_PAYLOAD], wire[TLP_MAX_WIRE];
        uint8_t len = (uint8_t)(rnd() % (TLP_MAX_PAYLOAD + 1));
        for (int i = 0; i < len; i++)
            payload[i] = (uint8_t)rnd();
        uint16_t seq = (uint16_t)rnd();
        uint8_t cmd = (uint8_t)rnd();
        size_t wl = tl_frame_encode(seq, cmd, payload, len, wire, sizeof wire);
        tl_rx_t rx;
        tl_rx_init(&rx);
        tl_frame_t f;
        uint8_t st = 0;
        tl_rx_result_t r = TL_RX_NONE;
        for (size_t i = 0; i < wl; i++)
            r = tl_rx_byte(&rx, wire[i], &f, &st);
        CHECK(r == TL_RX_FRAME && f.seq == seq && f.cmd == cmd && f.len == len &&
                  memcmp(f.payload, payload, len) == 0, "frame round trip");
        for (size_t bit = 0; bit < (wl - 1) * 8; bit++) {
            uint8_t bad[TLP_MAX_WIRE];
            memcpy(bad, wire, wl);
            bad[bit / 8] ^= (uint8_t)(1u << (bit % 8));
            tl_rx_init(&rx);
            int frames = 0;
            for (size_t i = 0; i < wl; i++)
                if (tl_rx_byte(&rx, bad[i], &f, &st) == TL_RX_FRAME)
                    frames++;
            CHECK(frames == 0, "bit flip %zu of a %zu-byte frame accepted", bit, wl);
        }
        /* truncated then delimited: an error, and the next frame still parses */
        tl_rx_init(&rx);
        size_t cut = 1 + rnd() % (wl - 1);
        for (size_t i = 0; i < cut; i++)
            (void)tl_rx_byte(&rx, wire[i], &f, &st);
        r = tl_rx_byte(&rx, 0, &f, &st);
        CHECK(r == TL_RX_ERROR || cut == wl - 1 || cut == 1, "truncated frame (%zu of %zu) not an error", cut, wl);
        for (size_t i = 0; i < wl; i++)
            r = tl_rx_byte(&rx, wire[i], &f, &st);
        CHECK(r == TL_RX_FRAME && f.seq == seq, "resynchronised after a truncated frame");
    }
    /* oversize: a long run of non-zero bytes */
    tl_rx_t rx;
    tl_rx_init(&rx);
    tl_frame_t f;
    uint8_t st = 0;
    for (int i = 0; i < 500; i++)
        (void)tl_rx_byte(&rx, (uint8_t)(1 + rnd() % 255), &f, &st);
    CHECK(tl_rx_byte(&rx, 0, &f, &st) == TL_RX_ERROR && st == TLP_ST_OVERSIZE, "oversize status %u", st);
    /* len field disagreeing with the bytes: LENGTH (CRC made to match) */
    uint8_t pkt[8] = {1, 0, 7, 3, 9, 9}, enc[16];
    tl_put_u16(&pkt[6], 0);
    uint8_t body[6] = {1, 0, 7, 3, 9, 9};
    uint16_t crc = tl_crc16(body, 6, 0xFFFFu);
    tl_put_u16(&pkt[6], crc);
    size_t el = tl_cobs_encode(pkt, 8, enc);
    tl_rx_init(&rx);
    for (size_t i = 0; i < el; i++)
        (void)tl_rx_byte(&rx, enc[i], &f, &st);
    CHECK(tl_rx_byte(&rx, 0, &f, &st) == TL_RX_ERROR && st == TLP_ST_LENGTH, "length status %u", st);
    /* sequence window */
    tl_seq_t s = {0, false};
    CHECK(tl_seq_is_new(&s, 0x1234), "any first seq");
    tl_seq_accept(&s, 0xFFF0);
    CHECK(!tl_seq_is_new(&s, 0xFFF0), "same seq is a replay");
    CHECK(!tl_seq_is_new(&s, 0xFF00), "older seq is a replay");
    CHECK(tl_seq_is_new(&s, 0x0005), "wrap-around is new");
    CHECK(!tl_seq_is_new(&s, (uint16_t)(0xFFF0 + 0x8000)), "half-window ahead is not new");
}

/* ---- servo core on the fake HAL -------------------------------------------- */

static tl_servo_t sv;
static uint8_t last_reply[TLP_MAX_PACKET];
static int last_reply_len;
static uint16_t host_seq;
static tl_rx_t reply_rx;

static bool capture_tx(const uint8_t *wire, uint32_t len)
{
    tl_frame_t f;
    uint8_t st;
    for (uint32_t i = 0; i < len; i++) {
        if (tl_rx_byte(&reply_rx, wire[i], &f, &st) == TL_RX_FRAME) {
            last_reply[0] = f.cmd;
            memcpy(&last_reply[1], f.payload, f.len);
            last_reply_len = f.len;
        } else {
            CHECK(wire[i] != 0u || i == 0u || i == len - 1u, "reply frame must decode");
        }
    }
    return true;
}

static void feed(const uint8_t *wire, size_t len)
{
    for (size_t i = 0; i < len; i++)
        tl_servo_rx_byte(&sv, wire[i], capture_tx);
}

/* Send one command, return its status (reply payload byte 0). */
static uint8_t send_cmd(uint8_t cmd, const uint8_t *payload, uint8_t len)
{
    uint8_t wire[TLP_MAX_WIRE];
    size_t wl = tl_frame_encode(++host_seq, cmd, payload, len, wire, sizeof wire);
    last_reply_len = -1;
    feed(wire, wl);
    CHECK(last_reply_len >= 1 && last_reply[0] == (cmd | TLP_REPLY_FLAG), "reply to 0x%02x", cmd);
    return last_reply[1];
}

static uint8_t set_param(uint8_t axis, uint8_t id, int32_t v)
{
    uint8_t p[6] = {axis, id};
    tl_put_u32(&p[2], (uint32_t)v);
    return send_cmd(TLP_CMD_SET_PARAM, p, 6);
}

static uint8_t enable(uint8_t mask, uint8_t on)
{
    uint8_t p[2] = {mask, on};
    return send_cmd(TLP_CMD_ENABLE, p, 2);
}

static uint8_t move(uint8_t axis, uint8_t mode, int32_t target)
{
    uint8_t p[6] = {axis, mode};
    tl_put_u32(&p[2], (uint32_t)target);
    return send_cmd(TLP_CMD_MOVE, p, 6);
}

static uint8_t clear(uint8_t mask) { return send_cmd(TLP_CMD_CLEAR_FAULT, &mask, 1); }

static void fresh(void)
{
    hal_fake_reset();
    tl_servo_init(&sv);
    tl_rx_init(&reply_rx);
    host_seq = (uint16_t)rnd();
}

static void ticks(int n)
{
    for (int i = 0; i < n; i++)
        tl_servo_tick(&sv);
}

static void test_servo_safety(void)
{
    fresh();
    CHECK(!hal_fake.pwm_on[0] && !hal_fake.pwm_on[1], "power-up: drives disabled");
    CHECK(move(0, 0, 100) == TLP_ST_STATE, "move while disabled refused");
    ticks(5);
    CHECK(!hal_fake.pwm_on[0] && sv.ax[0].faults == 0, "power-up latch is not a fault");

    /* enable acknowledges the reset latch; the set-point starts at the position */
    hal_fake.enc[0].pos = 1234;
    CHECK(enable(1, 1) == TLP_ST_OK && hal_fake.pwm_on[0] && !(hal_fake.safety & TL_HAL_SAFE_FORCED), "enable");
    ticks(1);
    CHECK(hal_fake.pwm_cmd[0] == 0, "no jump on enable: cmd %" PRId32, hal_fake.pwm_cmd[0]);
    CHECK(move(0, 0, 1334) == TLP_ST_OK, "move");
    ticks(1);
    int32_t expect = (int32_t)(((((int64_t)sv.ax[0].ctl.kp_q16 * 100 * 65536) >> 16) + 32768) >> 16);
    CHECK(hal_fake.pwm_cmd[0] == expect, "P command %" PRId32 " expected %" PRId32, hal_fake.pwm_cmd[0], expect);

    /* replay: the same frame again is refused and not executed */
    uint8_t p[6] = {0, 0};
    tl_put_u32(&p[2], 2000);
    uint8_t wire[TLP_MAX_WIRE];
    size_t wl = tl_frame_encode(++host_seq, TLP_CMD_MOVE, p, 6, wire, sizeof wire);
    feed(wire, wl);
    CHECK(last_reply[1] == TLP_ST_OK, "first copy executed");
    (void)move(0, 0, 1334);
    feed(wire, wl);
    CHECK(last_reply[1] == TLP_ST_REPLAY && (sv.ax[0].c.target_q16 >> 16) == 1334, "replay refused");

    /* e-stop: disabled in the same tick, latched, clear refused while pressed */
    hal_fake.safety |= TL_HAL_SAFE_ESTOP_IN | TL_HAL_SAFE_ESTOP | TL_HAL_SAFE_FORCED;
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && hal_fake.pwm_cmd[0] == 0 && (sv.ax[0].faults & TLP_FAULT_ESTOP), "e-stop");
    CHECK(clear(1) == TLP_ST_STATE && enable(1, 1) == TLP_ST_STATE, "clear refused while pressed");
    hal_fake.safety &= ~TL_HAL_SAFE_ESTOP_IN;
    CHECK(enable(1, 1) == TLP_ST_STATE, "enable refused while latched");
    CHECK(clear(3) == TLP_ST_OK && sv.ax[0].faults == 0 && sv.ax[1].faults == 0 && !hal_fake.pwm_on[0], "clear leaves it disabled");
    CHECK(enable(1, 1) == TLP_ST_OK, "enable after clear");

    /* link watchdog */
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_PERIOD_US, 1000) == TLP_ST_OK, "period");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_LINK_TIMEOUT_MS, 20) == TLP_ST_OK, "timeout");
    ticks(20);
    CHECK(hal_fake.pwm_on[0], "alive at the timeout");
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && (sv.ax[0].faults & TLP_FAULT_LINK), "link silent -> stop");
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover");

    /* following error and soft limits */
    CHECK(set_param(0, TLP_P_FOLLOW_LIMIT, 50) == TLP_ST_OK, "follow limit");
    CHECK(move(0, 0, 1234 + 51) == TLP_ST_OK, "move");
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && (sv.ax[0].faults & TLP_FAULT_FOLLOWING), "following");
    CHECK(clear(1) == TLP_ST_OK && enable(1, 1) == TLP_ST_OK, "recover");
    CHECK(set_param(0, TLP_P_SOFT_MAX, 1300) == TLP_ST_OK, "soft max");
    CHECK(move(0, 0, 1301) == TLP_ST_RANGE, "target beyond the soft limit");
    CHECK(set_param(0, TLP_P_SOFT_MIN, 1400) == TLP_ST_RANGE, "min above max refused");
    hal_fake.enc[0].pos = 1301;
    ticks(1);
    CHECK(!hal_fake.pwm_on[0] && (sv.ax[0].faults & TLP_FAULT_SOFT_LIMIT), "soft limit");
    hal_fake.enc[0].pos = 1234;
    CHECK(clear(1) == TLP_ST_OK, "clear");

    /* bridge fault and encoder fault on axis 1; hardware-forced safe */
    CHECK(enable(2, 1) == TLP_ST_OK, "enable 1: faults %u safety 0x%x", sv.ax[1].faults, hal_fake.safety);
    hal_fake.enc[1].bridge_fault = true;
    ticks(1);
    CHECK(!hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_BRIDGE), "bridge");
    CHECK(clear(2) == TLP_ST_STATE, "bridge fault present");
    hal_fake.enc[1].bridge_fault = false;
    CHECK(clear(2) == TLP_ST_OK && enable(2, 1) == TLP_ST_OK, "recover");
    hal_fake.enc[1].illegal = 3;
    ticks(1);
    CHECK(!hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_ENCODER), "encoder");
    CHECK(clear(2) == TLP_ST_OK && hal_fake.enc[1].illegal == 0, "encoder clear resets the count");
    CHECK(enable(2, 1) == TLP_ST_OK, "recover");
    hal_fake.safety |= TL_HAL_SAFE_WDOG | TL_HAL_SAFE_FORCED;
    ticks(1);
    CHECK(!hal_fake.pwm_on[1] && (sv.ax[1].faults & TLP_FAULT_HW_SAFE), "hardware watchdog");
    CHECK(hal_fake.irq_depth == 0, "critical sections balanced");

    /* a new link rate is handed to main.c, which applies it once the reply has gone out */
    CHECK(sv.baud_div_pending == 0u && (int32_t)hal_fake.baud_div == TLP_PARAM_INFO[tl_param_index(TLP_P_BAUD_DIV)].dflt[0],
          "default baud divisor applied at init");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_BAUD_DIV, 5207) == TLP_ST_OK && sv.baud_div_pending == 5207u,
          "9600 baud pending");
    CHECK(set_param(TLP_GLOBAL_AXIS, TLP_P_BAUD_DIV, 14) == TLP_ST_RANGE && sv.baud_div_pending == 5207u,
          "divisor below the UART's minimum refused");
}

/* Random and corrupted traffic: no parameter, enable or set-point changes. */
static void test_servo_flood(void)
{
    fresh();
    CHECK(enable(1, 1) == TLP_ST_OK, "enable");
    tl_servo_t before = sv;
    hal_fake_t hw = hal_fake;
    uint8_t templ[TLP_MAX_WIRE];
    uint8_t p[6] = {0, 0, 0x10, 0x27, 0, 0};
    size_t tl = tl_frame_encode((uint16_t)(host_seq + 1), TLP_CMD_MOVE, p, 6, templ, sizeof templ);
    unsigned frames = 0;
    for (int n = 0; n < 20000; n++) {
        uint8_t buf[200];
        size_t len;
        if (rnd() % 2) {
            len = rnd() % sizeof buf;
            for (size_t i = 0; i < len; i++)
                buf[i] = (uint8_t)rnd();
        } else {
            memcpy(buf, templ, tl);
            len = tl;
            int flips = 1 + (int)(rnd() % 3);
            for (int k = 0; k < flips; k++)
                buf[rnd() % (tl - 1)] ^= (uint8_t)(1u << (rnd() % 8));
            if (memcmp(buf, templ, tl) == 0)
                continue;   /* two flips of the same bit: that is the valid frame itself */
        }
        feed(buf, len);
        feed((const uint8_t *)"\0", 1);
        frames++;
    }
    /* a 2^-16 chance per random frame of a valid CRC: count only what the firmware accepted */
    CHECK(sv.cnt.frames_ok == before.cnt.frames_ok, "accepted %u frames of noise", sv.cnt.frames_ok - before.cnt.frames_ok);
    CHECK(memcmp(sv.ax[0].p, before.ax[0].p, sizeof sv.ax[0].p) == 0 &&
              memcmp(sv.ax[1].p, before.ax[1].p, sizeof sv.ax[1].p) == 0 && memcmp(sv.g, before.g, sizeof sv.g) == 0,
          "parameters changed by noise");
    CHECK(sv.ax[0].c.target_q16 == before.ax[0].c.target_q16 && sv.ax[0].enabled && !sv.ax[1].enabled &&
              hal_fake.pwm_on[0] == hw.pwm_on[0] && hal_fake.pwm_on[1] == hw.pwm_on[1],
          "motion state changed by noise");
    unsigned errs = (unsigned)sv.cnt.crc + sv.cnt.framing + sv.cnt.length + sv.cnt.oversize;
    CHECK(errs + 50u >= frames, "errors counted %u of %u chunks", errs, frames);
    printf("flood: %u chunks, %u counted as errors\n", frames, errs);
}

/* Trapezoid: speed <= vmax, speed change <= amax per sample, lands exactly, never overshoots. */
static void test_profile(void)
{
    for (int n = 0; n < 300; n++) {
        tl_ctl_params_t p = {.law = 1, .kp_q16 = 1000, .cmd_limit = 1023, .vel_mode = 1,
                             .vmax_cps = (int32_t)(1 + rnd() % 200000), .amax_cps2 = (int32_t)(1 + rnd() % 5000000)};
        tl_ctl_t c;
        uint32_t period = 200 + rnd() % 24800;
        tl_ctl_derive(&c, &p, period, 50000000u);
        int32_t start = (int32_t)(rnd() % 20000) - 10000, target = (int32_t)(rnd() % 20000) - 10000;
        tl_ctl_reset(&c, start, 0);
        tl_ctl_move(&c, target, true);
        int64_t prev_v = 0, prev_sp = c.sp_q16;
        int steps = 0;
        bool ok = true;
        while (c.moving && steps < 2000000) {
            (void)tl_ctl_step(&c, &p, start, 0, 0, 0, false);
            int64_t v = c.sp_q16 - prev_sp;
            int64_t dv = v - prev_v;
            if ((v < 0 ? -v : v) > c.vmax_q16 + c.amax_q16 || (dv < 0 ? -dv : dv) > c.amax_q16)
                ok = false;
            int64_t before = (int64_t)target * 65536 - prev_sp, after = (int64_t)target * 65536 - c.sp_q16;
            if ((before > 0 && after < 0) || (before < 0 && after > 0))
                ok = false;
            prev_v = v;
            prev_sp = c.sp_q16;
            steps++;
        }
        CHECK(ok && !c.moving && c.sp_q16 == (int64_t)target * 65536,
              "profile %d: vmax %" PRId32 " amax %" PRId32 " period %" PRIu32 " %d steps", n, p.vmax_cps, p.amax_cps2,
              period, steps);
    }
}

/* ---- line-driven control for the Python reference comparison ---------------- */

static int ctl_main(void)
{
    tl_ctl_params_t p = {0};
    tl_ctl_t c;
    memset(&c, 0, sizeof c);
    uint32_t period = 1000;
    char line[256];
    while (fgets(line, sizeof line, stdin)) {
        long long a[12] = {0};
        char op = line[0];
        int n = sscanf(line + 1, "%lld %lld %lld %lld %lld %lld %lld %lld %lld %lld %lld", &a[0], &a[1], &a[2],
                       &a[3], &a[4], &a[5], &a[6], &a[7], &a[8], &a[9], &a[10]);
        (void)n;
        switch (op) {
        case 'P':
            p = (tl_ctl_params_t){(uint32_t)a[0], (int32_t)a[1], (int32_t)a[2], (int32_t)a[3], (int32_t)a[4],
                                  (int32_t)a[5], (uint32_t)a[6], (int32_t)a[7], (int32_t)a[8]};
            period = (uint32_t)a[9];
            tl_ctl_derive(&c, &p, period, 50000000u);
            break;
        case 'R': tl_ctl_reset(&c, (int32_t)a[0], (uint32_t)a[1]); break;
        case 'M': tl_ctl_move(&c, (int32_t)a[0], a[1] != 0); break;
        case 'S': {
            int32_t cmd = tl_ctl_step(&c, &p, (int32_t)a[0], (uint32_t)a[1], (uint32_t)a[2], (uint32_t)a[4], a[3] != 0);
            printf("%" PRId32 " %" PRId64 " %" PRId32 " %" PRId64 "\n", cmd, c.sp_q16, c.vel_q8, c.integ_q32);
            break;
        }
        case 'G':
            printf("%" PRId32 " %" PRId32 "\n", tl_gain_raw_from_phys((int32_t)a[0], (int32_t)a[1], (int32_t)a[2]),
                   tl_gain_phys_from_raw((int32_t)a[3], (int32_t)a[1], (int32_t)a[2]));
            break;
        default: break;
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && strcmp(argv[1], "ctl") == 0)
        return ctl_main();
    uint64_t seed = argc >= 3 ? strtoull(argv[2], NULL, 0) : 0x5EEDu;
    rng_state = seed ? seed : 1u;
    printf("seed %" PRIu64 "\n", seed);
    test_link();
    test_servo_safety();
    test_servo_flood();
    test_profile();
    printf("%u checks, %u failures\n", checks, failures);
    return failures ? 1 : 0;
}
