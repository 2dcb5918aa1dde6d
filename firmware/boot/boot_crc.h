/* SPDX-License-Identifier: MIT */
/* CRC-32/ISO-HDLC (zlib, Ethernet) of the upload protocol, docs/bootloader.md. */
#ifndef BOOT_CRC_H
#define BOOT_CRC_H
#include <stdint.h>

#define BOOT_CRC_INIT 0xFFFFFFFFu   /* start value; the final CRC is ~state */

uint32_t boot_crc_byte(uint32_t state, uint8_t byte);

#endif
