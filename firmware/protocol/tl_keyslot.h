/* SPDX-License-Identifier: MIT */
/* The boot ROM's key slot (docs/security.md, 'Key provisioning'): the last
 * TLP_AUTH_KEY_SLOT_BYTES of the ROM hold magic, algorithm, the link key and
 * its check value HMAC(key, "TLKC")[:4]; the servo firmware (tl_auth.c) and
 * the bootloader (boot.c) both take their key from it through this one
 * function.  Layout from protocol.toml [auth] (tl_protocol.h). */
#ifndef TL_KEYSLOT_H
#define TL_KEYSLOT_H

#include <stdbool.h>
#include <stdint.h>

#include "tl_protocol.h"
#include "tl_sha256.h"

#define TL_KEYSLOT_KEY_OFS 8u                                         /* after magic, algorithm */
#define TL_KEYSLOT_CHECK_OFS (TL_KEYSLOT_KEY_OFS + TLP_AUTH_KEY_BYTES)
#define TL_KEYSLOT_CHECK_BYTES 4u

/* true with *k ready for HMAC if the slot holds a key: magic, algorithm and
 * check value right.  A blank or damaged slot is no key. */
bool tl_keyslot_load(const uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES], tl_hmac_key_t *k);

#endif
