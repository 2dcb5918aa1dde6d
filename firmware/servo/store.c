/* SPDX-License-Identifier: MIT */
/* The parameter store (store.h).  The record and the two slots are
 * protocol.toml's [store]; the flash is driven with the EPCS command set
 * (READ, WRITE ENABLE, READ STATUS, PAGE PROGRAM, SECTOR ERASE) through
 * hal_flash_select / hal_flash_xfer.
 *
 * Why two copies: a save erases a whole sector before writing it, and the
 * board may lose power at any moment of that.  A save therefore only ever
 * erases and writes the slot that does not hold the newest valid copy; until
 * its last word (the CRC) is programmed the new copy is invalid, and the old
 * one, untouched, is what the next start loads.  The CRC is
 * CRC-32/ISO-HDLC (the bootloader's, boot_crc.c) over the whole record.
 * Nothing here runs in the control interrupt: compiled for size (control.h). */
#include "store.h"

#include "boot_crc.h"
#include "servo_internal.h"

/* The record, as it lies in the flash: u32 words, little-endian (protocol.toml [store]).
 * Every parameter slot of the global array and of each axis's array is stored, in the
 * order of TLP_PARAM_INFO; layout names that order, so a firmware with other
 * parameters ignores the record (and starts with its defaults). */
typedef struct {
    uint32_t magic, seq, layout;
    int32_t g[TLP_PARAM_COUNT];
    int32_t p[TL_AXES][TLP_PARAM_COUNT];
    uint32_t crc;
} record_t;
_Static_assert(sizeof(record_t) <= TLP_STORE_SECTOR_BYTES,
               "the record fits its room");
/* The words go to and from the flash as they lie in memory. */
_Static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "little-endian words");

/* ---- EPCS commands ---------------------------------------------------------- */

TL_FOR_SIZE static void op_addr(uint8_t op, uint32_t addr)
{
    hal_flash_select(true);
    hal_flash_xfer(op);
    hal_flash_xfer((uint8_t)(addr >> 16));
    hal_flash_xfer((uint8_t)(addr >> 8));
    hal_flash_xfer((uint8_t)addr);
}

TL_FOR_SIZE static void flash_read(uint32_t addr, uint8_t *dst, uint32_t n)
{
    op_addr(TLP_STORE_OP_READ, addr);
    for (uint32_t i = 0; i < n; i++)
        dst[i] = hal_flash_xfer(0xFFu);
    hal_flash_select(false);
}

TL_FOR_SIZE static uint8_t read_status(void)
{
    hal_flash_select(true);
    hal_flash_xfer(TLP_STORE_OP_READ_STATUS);
    uint8_t st = hal_flash_xfer(0xFFu);
    hal_flash_select(false);
    return st;
}

/* WRITE ENABLE; false if the latch did not set (no flash answering). */
TL_FOR_SIZE static bool write_enable(void)
{
    hal_flash_select(true);
    hal_flash_xfer(TLP_STORE_OP_WRITE_ENABLE);
    hal_flash_select(false);
    return (read_status() & (TLP_STORE_STATUS_WEL | TLP_STORE_STATUS_WIP)) == TLP_STORE_STATUS_WEL;
}

/* Until the write in progress ends, at most twice the data sheet's maximum time. */
TL_FOR_SIZE static bool wait_ready(uint32_t max_us)
{
    uint32_t limit = (uint32_t)((uint64_t)max_us * 2u * (hal_clk_hz() / 1000000u));
    uint32_t t0 = hal_cycles();
    while (read_status() & TLP_STORE_STATUS_WIP)
        if (hal_cycles() - t0 > limit)
            return false;
    return true;
}

TL_FOR_SIZE static bool sector_erase(uint32_t addr)
{
    if (!write_enable())
        return false;
    op_addr(TLP_STORE_OP_SECTOR_ERASE, addr);
    hal_flash_select(false);
    return wait_ready(TLP_STORE_SECTOR_ERASE_US);
}

/* n bytes from addr, one PAGE PROGRAM per page they touch. */
TL_FOR_SIZE static bool program(uint32_t addr, const uint8_t *src, uint32_t n)
{
    while (n) {
        uint32_t room = TLP_STORE_PAGE_BYTES - (addr % TLP_STORE_PAGE_BYTES);
        uint32_t k = n < room ? n : room;
        if (!write_enable())
            return false;
        op_addr(TLP_STORE_OP_PAGE_PROGRAM, addr);
        for (uint32_t i = 0; i < k; i++)
            hal_flash_xfer(src[i]);
        hal_flash_select(false);
        if (!wait_ready(TLP_STORE_PAGE_PROGRAM_US))
            return false;
        addr += k;
        src += k;
        n -= k;
    }
    return true;
}

/* ---- the record -------------------------------------------------------------- */

TL_FOR_SIZE static uint32_t crc_words(const record_t *r)
{
    const uint8_t *b = (const uint8_t *)r;
    uint32_t c = BOOT_CRC_INIT;
    for (uint32_t i = 0; i < sizeof(record_t) - 4u; i++)
        c = boot_crc_byte(c, b[i]);
    return ~c;
}

/* A copy whose magic, layout and CRC check: true. */
TL_FOR_SIZE static bool read_record(uint32_t addr, record_t *r)
{
    const uint32_t head = 3u * 4u;      /* magic, seq, layout: an empty slot costs only these */
    flash_read(addr, (uint8_t *)r, head);
    if (r->magic != TLP_STORE_MAGIC || r->layout != TLP_PARAM_LAYOUT)
        return false;
    flash_read(addr + head, (uint8_t *)r + head, sizeof *r - head);
    return crc_words(r) == r->crc;
}

/* Two records: static, not on the stack of the command handler. */
static record_t rec_a, rec_b, rec_new;

/* The newest valid copy (the newer seq modulo 2^32 of two valid ones), or NULL. */
TL_FOR_SIZE static const record_t *newest(void)
{
    bool a = read_record(TLP_STORE_SLOT_A, &rec_a), b = read_record(TLP_STORE_SLOT_B, &rec_b);
    if (a && b)
        return (int32_t)(rec_b.seq - rec_a.seq) > 0 ? &rec_b : &rec_a;
    return a ? &rec_a : (b ? &rec_b : 0);
}

TL_FOR_SIZE static void build_record(const tl_servo_t *s, uint32_t seq, record_t *r)
{
    r->magic = TLP_STORE_MAGIC;
    r->seq = seq;
    r->layout = TLP_PARAM_LAYOUT;
    for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++) {
        r->g[k] = s->g[k];
        for (uint32_t ax = 0; ax < TL_AXES; ax++)
            r->p[ax][k] = s->ax[ax].p[k];
    }
    r->crc = crc_words(r);
}

/* Same parameter values (the header and the CRC aside). */
TL_FOR_SIZE static bool same_values(const record_t *a, const record_t *b)
{
    for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++) {
        if (a->g[k] != b->g[k])
            return false;
        for (uint32_t ax = 0; ax < TL_AXES; ax++)
            if (a->p[ax][k] != b->p[ax][k])
                return false;
    }
    return true;
}

TL_FOR_SIZE static bool in_range(uint32_t k, int32_t v)
{
    int32_t lo, hi;
    tl_param_range(k, &lo, &hi);
    return v >= lo && v <= hi;
}

TL_FOR_SIZE void tl_store_load(tl_servo_t *s)
{
    const record_t *r = newest();
    if (!r)
        return;
    for (uint32_t k = 0; k < TLP_PARAM_COUNT; k++) {
        if (in_range(k, r->g[k]))
            s->g[k] = r->g[k];
        for (uint32_t ax = 0; ax < TL_AXES; ax++)
            if (in_range(k, r->p[ax][k]))
                s->ax[ax].p[k] = r->p[ax][k];
    }
}

TL_FOR_SIZE void tl_store_report(const tl_servo_t *s, tl_store_report_t *rep)
{
    const record_t *r = newest();
    rep->saved = r != 0;
    rep->seq = r ? r->seq : 0u;
    build_record(s, rep->seq, &rec_new);
    rep->differs = !r || !same_values(r, &rec_new);
}

TL_FOR_SIZE uint8_t tl_store_save(tl_servo_t *s, uint8_t *why)
{
    if (tl_any_enabled(s))
        return refuse(why, TLP_WHY_ENABLED);
    const record_t *r = newest();
    /* the slot without the newest valid copy: the newest stays whole whatever happens */
    uint32_t slot = (r == &rec_a) ? TLP_STORE_SLOT_B : TLP_STORE_SLOT_A;
    build_record(s, r ? r->seq + 1u : 1u, &rec_new);
    if (!sector_erase(slot) || !program(slot, (const uint8_t *)&rec_new, sizeof rec_new))
        return TLP_ST_STORE;
    return (read_record(slot, &rec_a) && rec_a.seq == rec_new.seq && same_values(&rec_a, &rec_new)) ? TLP_ST_OK
                                                                                                   : TLP_ST_STORE;
}

TL_FOR_SIZE uint8_t tl_store_command(tl_servo_t *s, uint8_t op, uint8_t *rep, uint8_t *why)
{
    if (op > 1u)
        return refuse(why, TLP_WHY_CHOICE);
    if (op == 1u) {
        uint8_t st = tl_store_save(s, why);
        if (st != TLP_ST_OK)
            return st;
    }
    tl_store_report_t r;
    tl_store_report(s, &r);
    rep[TLP_SAVE_REP_SAVED] = r.saved;
    rep[TLP_SAVE_REP_DIFFERS] = r.differs;
    tl_put_u32(&rep[TLP_SAVE_REP_SEQ], r.seq);
    return TLP_ST_OK;
}
