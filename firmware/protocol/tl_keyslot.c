/* SPDX-License-Identifier: MIT */
/* The boot ROM's key slot (tl_keyslot.h). */
#include "tl_keyslot.h"

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

bool tl_keyslot_load(const uint8_t slot[TLP_AUTH_KEY_SLOT_BYTES], tl_hmac_key_t *k)
{
    if (le32(slot) != TLP_AUTH_KEY_SLOT_MAGIC || le32(&slot[4]) != TLP_AUTH_KEY_SLOT_ALGORITHM)
        return false;
    tl_hmac_key(k, &slot[TL_KEYSLOT_KEY_OFS], TLP_AUTH_KEY_BYTES);
    uint8_t mac[TL_SHA256_BYTES];
    tl_hmac_t m;
    tl_hmac_init(&m, k);
    tl_hmac_update(&m, (const uint8_t *)TLP_AUTH_LABEL_CHECK, TLP_AUTH_LABEL_BYTES);
    tl_hmac_final(&m, mac);
    /* a damaged slot (a flipped ROM bit, a half-written key) is no key, not a wrong one */
    return tl_ct_equal(mac, &slot[TL_KEYSLOT_CHECK_OFS], TL_KEYSLOT_CHECK_BYTES) != 0;
}
