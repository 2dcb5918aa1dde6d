/* SPDX-License-Identifier: MIT */
/* Servo firmware entry: the machine-timer interrupt runs one control
 * iteration of both axes every PERIOD_US (servo.c, tl_servo_tick); the main
 * loop moves bytes between the UART and the link layer and sends telemetry.
 *
 * Measured here and reported over the link (STATUS): the worst cycles of one
 * control iteration (mcycle around tl_servo_tick), the worst lateness of
 * the interrupt against its mtimecmp deadline (the jitter of the period) and
 * the periods overrun (the next deadline already past when an iteration ended).
 * The SoC's hardware watchdog was armed by the boot ROM before this image
 * started (its timeout cannot be changed from here); every control
 * iteration feeds it with the kick sequence.  If the interrupt stops, the
 * watchdog expires and the SoC latch and the board's drive interlock switch
 * the drives off; they stay off until the operator re-arms with SW[0]. */
#include <stdbool.h>
#include <stdint.h>

#include "hal.h"
#include "servo.h"
#include "torqueloop_regs.h"

#define TX_RING 512u          /* bytes; a power of two */
#define RX_RING 256u          /* bytes; a power of two */

static tl_servo_t servo;
static volatile uint64_t deadline;
static uint8_t tx_ring[TX_RING];
static volatile uint32_t tx_head, tx_tail;
static uint8_t rx_ring[RX_RING];
static volatile uint32_t rx_head, rx_tail;
static volatile uint32_t rx_lost;

static uint32_t mcycle(void)
{
    uint32_t v;
    __asm__ volatile("csrr %0, mcycle" : "=r"(v));
    return v;
}

static void arm_timer(uint64_t t)
{
    /* High word to all ones first: no spurious interrupt while the low half moves. */
    TL_TIMER_MTIMECMP_HI = 0xFFFFFFFFu;
    TL_TIMER_MTIMECMP_LO = (uint32_t)t;
    TL_TIMER_MTIMECMP_HI = (uint32_t)(t >> 32);
}

static uint64_t mtime(void)
{
    uint32_t hi, lo;
    do {
        hi = TL_TIMER_MTIME_HI;
        lo = TL_TIMER_MTIME_LO;
    } while (hi != TL_TIMER_MTIME_HI);
    return ((uint64_t)hi << 32) | lo;
}

static inline void kick_watchdog(void)
{
    TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_A;
    TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_B;
}

__attribute__((interrupt("machine"))) static void trap_handler(void)
{
    uint32_t cause;
    __asm__ volatile("csrr %0, mcause" : "=r"(cause));
    if (cause == 0x80000007u) {   /* machine timer */
        uint64_t due = deadline;
        uint32_t late = TL_TIMER_MTIME_LO - (uint32_t)due;
        uint32_t c0 = mcycle();
        tl_servo_tick(&servo);
        uint32_t period = servo.period_cycles;
        kick_watchdog();
        uint64_t next = due + period;
        /* The low word of mtime decides whether the next deadline has passed
         * (an overrun is far shorter than 2^31 clocks); the full time only then. */
        if (TL_UNLIKELY((int32_t)(TL_TIMER_MTIME_LO - (uint32_t)next) >= 0)) {
            /* Overrun: the iteration (plus the link interrupts) took more than a period.
             * Re-anchor instead of firing back-to-back to catch up, which would starve
             * the main loop and the link for good. */
            if (servo.overruns != 0xFFFFFFFFu)
                servo.overruns++;
            next = mtime() + period;
        }
        deadline = next;
        /* the common path falls through (taken forward branches cost 4 cycles on tl_cpu_pipe) */
        if (TL_LIKELY((uint32_t)(next >> 32) == (uint32_t)(due >> 32)))
            TL_TIMER_MTIMECMP_LO = (uint32_t)next;   /* raising the low word alone never fires early */
        else
            arm_timer(next);
        uint32_t used = mcycle() - c0;
        if (used > servo.loop_cycles_max)
            servo.loop_cycles_max = used;
        if (late > servo.jitter_cycles_max && late < period)
            servo.jitter_cycles_max = late;
        return;
    }
    if (cause == 0x8000000Bu) {   /* machine external: UART RX through the INTC */
        /* The 16-byte hardware FIFO lasts 16 byte times (139 us at 115200 baud); the main
         * loop can be busier than that (reply and telemetry encoding plus a control
         * iteration), so the bytes move to a software ring here.  Clear the pending bit
         * first, then drain to empty: a byte arriving after the drain raises a new edge. */
        TL_INTC_PENDING = TL_INTC_PENDING_UART_RX_MSK;
        uint32_t rx;
        while ((rx = TL_UART_RX_DATA) & TL_UART_RX_DATA_VALID_MSK) {
            uint32_t head = rx_head;
            if (head - rx_tail < RX_RING) {
                rx_ring[head & (RX_RING - 1u)] = (uint8_t)(rx & TL_UART_RX_DATA_DATA_MSK);
                rx_head = head + 1u;
            } else {
                rx_lost++;
            }
        }
        return;
    }
    /* Anything else is a firmware bug: drives off, stop here (the watchdog
     * expires because nothing kicks it any more). */
    hal_pwm_enable(0, false, true);
    hal_pwm_enable(1, false, true);
    for (;;)
        TL_GPIO_HEX_HI = 0x7979u;   /* "EE" on HEX5/HEX4 */
}

static bool tx_push_reserve(const uint8_t *wire, uint32_t len, uint32_t reserve)
{
    uint32_t head = tx_head;
    if (TX_RING - (head - tx_tail) < len + reserve)
        return false;
    for (uint32_t i = 0; i < len; i++)
        tx_ring[(head + i) & (TX_RING - 1u)] = wire[i];
    tx_head = head + len;
    return true;
}

static bool tx_push(const uint8_t *wire, uint32_t len) { return tx_push_reserve(wire, len, 0u); }

/* telemetry leaves room for a reply: a busy stream never starves the commands */
static bool tx_push_telemetry(const uint8_t *wire, uint32_t len) { return tx_push_reserve(wire, len, TLP_MAX_WIRE); }

static void tx_pump(void)
{
    while (tx_tail != tx_head && (TL_UART_STATUS & TL_UART_STATUS_TX_READY_MSK)) {
        TL_UART_TX_DATA = tx_ring[tx_tail & (TX_RING - 1u)];
        tx_tail++;
    }
}

static void tx_drain(void)
{
    while (tx_tail != tx_head)
        tx_pump();
    while (!(TL_UART_STATUS & TL_UART_STATUS_TX_IDLE_MSK)) {
    }
}

static void jump_to_bootloader(void)
{
    /* Drives are already off (servo.c); stop the timer and interrupts and
     * enter the boot ROM at its reset address.  The watchdog stays armed:
     * the bootloader feeds it. */
    tx_drain();
    hal_irq_off();
    arm_timer(0xFFFFFFFFFFFFFFFFull);
    kick_watchdog();
    void (*boot)(void) = (void (*)(void))(uintptr_t)TL_BOOT_ROM_BASE;
    boot();
}

int main(void)
{
    tl_servo_init(&servo);
    TL_GPIO_HEX_HI = 0u;
    TL_INTC_PENDING = 0xFFFFFFFFu;
    TL_INTC_ENABLE = TL_INTC_PENDING_UART_RX_MSK;
    /* A byte that arrived before the clear above (the host, or the RN-XV's
     * *OPEN*, talking right after start-up) raises no new event: re-raise it,
     * or the link would stay deaf with data waiting in the FIFO. */
    if (TL_UART_STATUS & TL_UART_STATUS_RX_VALID_MSK)
        TL_INTC_SET = TL_INTC_PENDING_UART_RX_MSK;
    kick_watchdog();
    deadline = mtime() + tl_servo_period_cycles(&servo);
    arm_timer(deadline);
    __asm__ volatile("csrw mtvec, %0" : : "r"(&trap_handler));
    __asm__ volatile("csrs mie, %0" : : "r"((1u << 7) | (1u << 11)));   /* MTIE, MEIE */
    hal_irq_on();

    uint32_t tick_period = tl_servo_period_cycles(&servo);
    for (;;) {
        while (rx_tail != rx_head) {
            uint8_t b = rx_ring[rx_tail & (RX_RING - 1u)];
            rx_tail = rx_tail + 1u;
            tl_servo_rx_byte(&servo, b, tx_push);
        }
        tl_servo_stream_telemetry(&servo, tx_push_telemetry);
        tx_pump();
        uint32_t period = tl_servo_period_cycles(&servo);
        if (period != tick_period) {
            /* The new period starts now: the next tick is one new period away,
             * not at the deadline computed with the old one.  The watchdog's
             * timeout (the boot ROM's, at least 4 of the longest periods) does
             * not follow the period, so neither change can starve it. */
            hal_irq_off();
            deadline = mtime() + period;
            arm_timer(deadline);
            hal_irq_on();
            tick_period = period;
        }
        if (servo.baud_div_pending) {
            tx_drain();
            hal_set_baud_div(servo.baud_div_pending);
            servo.baud_div_pending = 0;
        }
        if (servo.bootloader_req)
            jump_to_bootloader();
    }
}
