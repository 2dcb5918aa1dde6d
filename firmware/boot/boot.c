/* SPDX-License-Identifier: MIT */
/* torqueloop boot ROM bootloader (docs/bootloader.md).
 *
 * After reset (or a jump to the reset vector) it quiesces the peripherals,
 * says "TLBW\n" and listens on the UART for BOOT_WINDOW_CYCLES for an upload
 * frame: sync, header with its own CRC-32, image with a CRC-32, and the
 * image's MAC under the key in this ROM's key slot (docs/security.md).  An
 * image whose CRC and MAC are good is started; anything else is answered
 * with an error reply, and the factory image stored in this ROM is copied
 * over RAM and started instead, so a failed, interrupted or unsigned upload
 * never runs.  A ROM without a key refuses every upload.
 *
 * Before anything else it arms the SoC's hardware watchdog (BOOT_WDOG_CYCLES):
 * from then until reset nothing can disarm or lengthen it, so every image
 * it starts runs watched and must feed it with the kick sequence.  The
 * bootloader feeds it in every loop while it waits or copies.
 *
 * Runs from ROM with its stack in the top BOOT_STACK_BYTES of RAM, which an
 * upload never reaches; no .data, no .bss (boot.ld checks).  The constants
 * come from boot_proto.h, generated from torqueloop/spec/bootproto.py. */
#include <stdint.h>

#include "boot_crc.h"
#include "boot_proto.h"
#include "tl_keyslot.h"
#include "tl_sha256.h"
#include "torqueloop_regs.h"

#define RX_NONE (-1)

/* The window and gap constants are kept in the image (not only folded into
 * instructions) so a test can read the real values from the ELF. */
#define BOOT_PARAM __attribute__((section(".rodata.boot_param")))  /* GCC puts const volatile in .data */
BOOT_PARAM const volatile uint32_t boot_window_cycles = BOOT_WINDOW_CYCLES;
BOOT_PARAM const volatile uint32_t boot_gap_cycles = BOOT_GAP_CYCLES;

static const uint8_t sync_bytes[4] = BOOT_SYNC_BYTES;

struct factory_desc {
    uint32_t magic;
    uint32_t length;
    uint32_t crc;
    uint32_t load_addr;
    uint32_t image[];
};

/* At TL_BOOT_ROM_BASE + BOOT_FACTORY_OFS, placed by the generated boot.ld
 * (a symbol rather than a cast constant: GCC 12 rejects accesses through
 * pointers it knows to be near address 0). */
extern const volatile struct factory_desc boot_factory;
/* The key slot: the last TLP_AUTH_KEY_SLOT_BYTES of this ROM (boot.ld). */
extern const uint8_t boot_key_slot[TLP_AUTH_KEY_SLOT_BYTES];

#define BOOT_HASH_PIECE 4096u

static void kick(void)
{
    TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_A;
    TL_SYS_WDOG_KICK = TL_SYS_WDOG_KICK_KEY_KICK_B;
}

/* Armed once after reset; a jump here from a running image finds it armed
 * (the writes are then ignored) and just feeds it. */
static void arm_watchdog(void)
{
    TL_SYS_WDOG_LOAD = BOOT_WDOG_CYCLES;
    TL_SYS_WDOG_ARM = TL_SYS_WDOG_ARM_KEY_ARM_KEY;
    kick();
}

static uint32_t now(void)
{
    /* mtime low word: intervals up to 85 s by unsigned subtraction.  Every
     * waiting loop reads it, so the watchdog is fed here. */
    kick();
    return TL_TIMER_MTIME_LO;
}

static void put(uint8_t c)
{
    while (!(TL_UART_STATUS & TL_UART_STATUS_TX_READY_MSK))
        kick();
    TL_UART_TX_DATA = c;
}

static void reply(char code)
{
    put('T');
    put('L');
    put('B');
    put((uint8_t)code);
    put('\n');
}

static void tx_wait_idle(void)
{
    while (!(TL_UART_STATUS & TL_UART_STATUS_TX_IDLE_MSK))
        kick();
}

/* Next received byte, or RX_NONE after `limit` cycles without one. */
static int get(uint32_t limit)
{
    uint32_t t0 = now();
    for (;;) {
        uint32_t r = TL_UART_RX_DATA;   /* each read pops one byte */
        if (r & TL_UART_RX_DATA_VALID_MSK)
            return (int)(r & 0xFFu);
        if (now() - t0 >= limit)
            return RX_NONE;
    }
}

/* Whatever the code that jumped here left running: drives, interrupts,
 * timer, watchdog, UART mode.  After a reset all of this is already so. */
static void quiesce(void)
{
    /* drives off; the hardware limit block stays on (its reset state) */
    TL_AXIS0_PWM_CTRL = TL_AXIS_PWM_CTRL_LIMIT_EN_MSK;
    TL_AXIS0_PWM_CMD = 0u;
    TL_AXIS1_PWM_CTRL = TL_AXIS_PWM_CTRL_LIMIT_EN_MSK;
    TL_AXIS1_PWM_CMD = 0u;
    TL_INTC_ENABLE = 0u;
    TL_INTC_PENDING = 0xFFFFFFFFu;
    TL_TIMER_MTIMECMP_HI = 0xFFFFFFFFu;
    TL_TIMER_MTIMECMP_LO = 0xFFFFFFFFu;
    TL_TIMER_MSIP = 0u;
    /* Flow control off first: a peer holding CTS must not stall the drain. */
    TL_UART_CTRL = 0u;
    tx_wait_idle();
    TL_UART_BAUD_DIV = BOOT_BAUD_DIV;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* One upload attempt.  Returns BOOT_REPLY_OK with the image in RAM (its CRC
 * and MAC checked), an error reply code, or 0 if the window passed in
 * silence.  forever: no window.  key: the ROM's key, 0 if it has none. */
static char receive(int forever, const tl_hmac_key_t *key)
{
    uint32_t t0 = now();
    uint32_t skipped = 0;
    unsigned match = 0;

    while (match < sizeof sync_bytes) {
        kick();
        uint32_t r = TL_UART_RX_DATA;
        if (r & TL_UART_RX_DATA_VALID_MSK) {
            uint8_t b = (uint8_t)r;
            if (b == sync_bytes[match]) {
                match++;
            } else {
                /* The sync has no prefix that is also a suffix of a partial
                 * match, so a mismatch restarts at 0 or 1. */
                skipped += match + 1u;
                match = (b == sync_bytes[0]) ? 1u : 0u;
            }
        } else if (!forever && now() - t0 >= boot_window_cycles) {
            return (skipped || match) ? BOOT_REPLY_GARBAGE : 0;
        }
    }

    uint8_t hdr[BOOT_HEADER_BYTES + 4];
    uint32_t crc = BOOT_CRC_INIT;
    for (unsigned i = 0; i < sizeof hdr; i++) {
        int b = get(boot_gap_cycles);
        if (b == RX_NONE)
            return BOOT_REPLY_TIMEOUT;
        hdr[i] = (uint8_t)b;
        if (i < BOOT_HEADER_BYTES)
            crc = boot_crc_byte(crc, (uint8_t)b);
    }
    if (~crc != le32(&hdr[16]) || hdr[0] != BOOT_VERSION || hdr[1] || hdr[2] || hdr[3]
        || le32(&hdr[4]) != BOOT_LOAD_ADDR)
        return BOOT_REPLY_BAD_HEADER;
    uint32_t length = le32(&hdr[8]);
    if (length == 0u || length > BOOT_MAX_IMAGE_BYTES)
        return BOOT_REPLY_BAD_LENGTH;
    if (key == 0)
        return BOOT_REPLY_NO_KEY;

    /* Straight into RAM: on any failure the factory copy overwrites it. */
    volatile uint8_t *dst = (volatile uint8_t *)BOOT_LOAD_ADDR;
    crc = BOOT_CRC_INIT;
    for (uint32_t i = 0; i < length; i++) {
        int b = get(boot_gap_cycles);
        if (b == RX_NONE)
            return BOOT_REPLY_TIMEOUT;
        dst[i] = (uint8_t)b;
        crc = boot_crc_byte(crc, (uint8_t)b);
    }
    uint8_t tag[BOOT_TAG_BYTES];
    for (unsigned i = 0; i < sizeof tag; i++) {
        int b = get(boot_gap_cycles);
        if (b == RX_NONE)
            return BOOT_REPLY_TIMEOUT;
        tag[i] = (uint8_t)b;
    }
    if (~crc != le32(&hdr[12]))
        return BOOT_REPLY_BAD_CRC;
    /* The MAC over the header and the image as they stand in RAM, after the
     * last byte: hashing runs ~200 cycles a byte, slower than the UART at
     * 1 Mbaud fills the 16-byte RX FIFO, so not on the fly. */
    tl_hmac_t m;
    uint8_t mac[TL_SHA256_BYTES];
    tl_hmac_init(&m, key);
    tl_hmac_update(&m, (const uint8_t *)BOOT_LABEL_UPLOAD, 4u);
    tl_hmac_update(&m, hdr, BOOT_HEADER_BYTES);
    /* ~200 cycles a byte: a 63 KiB image takes ~250 ms, longer than the
     * hardware watchdog's 100 ms, so it is fed between 4 KiB pieces (16 ms). */
    for (uint32_t done = 0; done < length; done += BOOT_HASH_PIECE) {
        uint32_t n = length - done < BOOT_HASH_PIECE ? length - done : BOOT_HASH_PIECE;
        tl_hmac_update(&m, (const uint8_t *)(BOOT_LOAD_ADDR + done), n);
        kick();
    }
    tl_hmac_final(&m, mac);
    return tl_ct_equal(mac, tag, BOOT_TAG_BYTES) ? BOOT_REPLY_OK : BOOT_REPLY_AUTH;
}

/* Let the rest of a rejected frame pass (until the line is quiet for a gap),
 * so the factory firmware's link parser does not start on it; bounded by one
 * largest frame so a babbling line cannot keep the board from booting. */
static void drain(void)
{
    for (uint32_t n = 0; n < BOOT_MAX_IMAGE_BYTES + 64u; n++) {
        if (get(boot_gap_cycles) == RX_NONE)
            return;
    }
}

/* Copy the factory image from ROM to RAM and check its CRC-32 in RAM.
 * Returns 0 if the ROM holds no valid factory image. */
static int load_factory(void)
{
    const volatile struct factory_desc *d = &boot_factory;
    uint32_t length = d->length;
    if (d->magic != BOOT_FACTORY_MAGIC || d->load_addr != BOOT_LOAD_ADDR || length == 0u
        || length > BOOT_FACTORY_MAX_BYTES)
        return 0;
    const volatile uint32_t *src = d->image;
    volatile uint32_t *dst = (volatile uint32_t *)BOOT_LOAD_ADDR;
    for (uint32_t i = 0; i < (length + 3u) / 4u; i++)
        dst[i] = src[i];
    kick();
    const volatile uint8_t *ram = (const volatile uint8_t *)BOOT_LOAD_ADDR;
    uint32_t crc = BOOT_CRC_INIT;
    for (uint32_t i = 0; i < length; i++) {
        if ((i & 1023u) == 0u)
            kick();
        crc = boot_crc_byte(crc, ram[i]);
    }
    return ~crc == d->crc;
}

static void __attribute__((noreturn)) start_image(void)
{
    tx_wait_idle();                  /* the image may change the baud rate */
    TL_INTC_PENDING = 0xFFFFFFFFu;   /* our own UART traffic is no event for it */
    kick();                          /* a full timeout for the image to start feeding it */
    void (*entry)(void) = (void (*)(void))BOOT_LOAD_ADDR;
    entry();
    for (;;) {
    }
}

void __attribute__((noreturn)) boot_main(void);

void boot_main(void)
{
    arm_watchdog();
    quiesce();
    /* The key first (~55 000 cycles, four compressions): during a frame the
     * 16-byte RX FIFO would overflow at 1 Mbaud. */
    tl_hmac_key_t key;
    const tl_hmac_key_t *k = tl_keyslot_load(boot_key_slot, &key) ? &key : 0;
    int forever = 0;
    for (;;) {
        reply(BOOT_REPLY_WINDOW);
        char r = receive(forever, k);
        if (r == BOOT_REPLY_OK) {
            reply(BOOT_REPLY_OK);
            start_image();
        }
        if (r) {
            reply(r);
            drain();
        }
        if (load_factory()) {
            reply(BOOT_REPLY_FACTORY);
            start_image();
        }
        reply(BOOT_REPLY_NO_FACTORY);
        forever = 1;
    }
}
