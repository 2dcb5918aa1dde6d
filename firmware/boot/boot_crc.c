/* SPDX-License-Identifier: MIT */
/* CRC-32/ISO-HDLC, reflected polynomial 0xEDB88320, one nibble at a time:
 * a 64-byte table instead of 1 KiB keeps the bootloader inside its 2 KiB ROM
 * slot, and two table steps per byte (about 20 instructions, ~100 cycles at
 * the CPU's CPI of 5) still keep up with the UART (500 cycles per byte even
 * at 1 Mbaud).  Also compiled on the host by tests/test_bootproto.py and
 * checked against zlib. */
#include "boot_crc.h"

static const uint32_t crc_nibble[16] = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu,
    0x76DC4190u, 0x6B6B51F4u, 0x4DB26158u, 0x5005713Cu,
    0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
    0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
};

uint32_t boot_crc_byte(uint32_t state, uint8_t byte)
{
    state ^= byte;
    state = (state >> 4) ^ crc_nibble[state & 0xFu];
    state = (state >> 4) ^ crc_nibble[state & 0xFu];
    return state;
}
