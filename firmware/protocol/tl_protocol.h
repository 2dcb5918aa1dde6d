/* SPDX-License-Identifier: MIT */
/* Generated from torqueloop/spec/protocol.toml by torqueloop.flow.generate - do not edit. */
#ifndef TL_PROTOCOL_H
#define TL_PROTOCOL_H

#include <stdint.h>

#define TLP_VERSION 0x4u
#define TLP_MAX_PAYLOAD 0x40u
#define TLP_HEADER_BYTES 0x4u
#define TLP_CRC_BYTES 0x2u
#define TLP_REPLY_FLAG 0x80u
#define TLP_TELEMETRY_CMD 0xC0u
#define TLP_ERROR_CMD 0xFFu
#define TLP_SEQ_WINDOW 0x8000u
#define TLP_BOOTLOADER_MAGIC 0xB00710ADu
#define TLP_FIRMWARE_VERSION 0x100u
#define TLP_MAX_PACKET 70u
#define TLP_MAX_ENCODED 71u
#define TLP_MAX_WIRE 73u  /* 0x00 COBS 0x00 */

#define TLP_ST_OK 0u
#define TLP_ST_CRC 1u
#define TLP_ST_FRAMING 2u
#define TLP_ST_LENGTH 3u
#define TLP_ST_OVERSIZE 4u
#define TLP_ST_UNKNOWN_CMD 5u
#define TLP_ST_BAD_ARG 6u
#define TLP_ST_RANGE 7u
#define TLP_ST_REPLAY 8u
#define TLP_ST_STATE 9u
#define TLP_ST_LOOSEN 10u
#define TLP_ST_NOT_HOMED 11u
#define TLP_ST_AUTH 12u
#define TLP_ST_NO_SESSION 13u
#define TLP_ST_NO_KEY 14u
#define TLP_ST_STORE 15u
/* the rule that refused a command: byte TLP_REPLY_WHY of its error reply */
#define TLP_REPLY_WHY 1u
#define TLP_WHY_NONE 0u
#define TLP_WHY_AXIS 1u
#define TLP_WHY_PARAM 2u
#define TLP_WHY_SCOPE 3u
#define TLP_WHY_CHOICE 4u
#define TLP_WHY_BELOW_MIN 5u
#define TLP_WHY_ABOVE_MAX 6u
#define TLP_WHY_SOFT_ORDER 7u
#define TLP_WHY_PW_ORDER 8u
#define TLP_WHY_CARRIER 9u
#define TLP_WHY_GAIN 10u
#define TLP_WHY_TIGHTEN 11u
#define TLP_WHY_OUTSIDE_SOFT 12u
#define TLP_WHY_LIMIT 13u
#define TLP_WHY_FOLLOW 14u
#define TLP_WHY_DISABLED 15u
#define TLP_WHY_HOMING 16u
#define TLP_WHY_FAULT 17u
#define TLP_WHY_ESTOP 18u
#define TLP_WHY_FORCED 19u
#define TLP_WHY_NO_SWITCHES 20u
#define TLP_WHY_NOT_HOMED 21u
#define TLP_WHY_CAUSE 22u
#define TLP_WHY_AXES_ENABLED 23u
#define TLP_WHY_HAS_SWITCHES 24u
#define TLP_WHY_HOME_POS_FROZEN 25u
#define TLP_WHY_CMD_LIMIT 26u
#define TLP_WHY_ENABLED 27u
/* the status a rule comes with (a constant rule folds to a constant) */
static inline uint8_t tlp_why_status(uint8_t why)
{
    switch (why) {
    case TLP_WHY_AXIS: return TLP_ST_BAD_ARG;
    case TLP_WHY_PARAM: return TLP_ST_BAD_ARG;
    case TLP_WHY_SCOPE: return TLP_ST_BAD_ARG;
    case TLP_WHY_CHOICE: return TLP_ST_BAD_ARG;
    case TLP_WHY_BELOW_MIN: return TLP_ST_RANGE;
    case TLP_WHY_ABOVE_MAX: return TLP_ST_RANGE;
    case TLP_WHY_SOFT_ORDER: return TLP_ST_RANGE;
    case TLP_WHY_PW_ORDER: return TLP_ST_RANGE;
    case TLP_WHY_CARRIER: return TLP_ST_RANGE;
    case TLP_WHY_GAIN: return TLP_ST_RANGE;
    case TLP_WHY_TIGHTEN: return TLP_ST_LOOSEN;
    case TLP_WHY_OUTSIDE_SOFT: return TLP_ST_RANGE;
    case TLP_WHY_LIMIT: return TLP_ST_RANGE;
    case TLP_WHY_FOLLOW: return TLP_ST_RANGE;
    case TLP_WHY_DISABLED: return TLP_ST_STATE;
    case TLP_WHY_HOMING: return TLP_ST_STATE;
    case TLP_WHY_FAULT: return TLP_ST_STATE;
    case TLP_WHY_ESTOP: return TLP_ST_STATE;
    case TLP_WHY_FORCED: return TLP_ST_STATE;
    case TLP_WHY_NO_SWITCHES: return TLP_ST_STATE;
    case TLP_WHY_NOT_HOMED: return TLP_ST_NOT_HOMED;
    case TLP_WHY_CAUSE: return TLP_ST_STATE;
    case TLP_WHY_AXES_ENABLED: return TLP_ST_STATE;
    case TLP_WHY_HAS_SWITCHES: return TLP_ST_STATE;
    case TLP_WHY_HOME_POS_FROZEN: return TLP_ST_LOOSEN;
    case TLP_WHY_CMD_LIMIT: return TLP_ST_RANGE;
    case TLP_WHY_ENABLED: return TLP_ST_STATE;
    default: return TLP_ST_OK;
    }
}

#define TLP_FAULT_ESTOP 0x0001u
#define TLP_FAULT_BRIDGE 0x0002u
#define TLP_FAULT_FOLLOWING 0x0004u
#define TLP_FAULT_SOFT_LIMIT 0x0008u
#define TLP_FAULT_LINK 0x0010u
#define TLP_FAULT_ENCODER 0x0020u
#define TLP_FAULT_HW_SAFE 0x0040u
#define TLP_FAULT_RUNAWAY 0x0080u
#define TLP_FAULT_LIMIT_NEG 0x0100u
#define TLP_FAULT_LIMIT_POS 0x0200u
/* faults that only block motion toward their end: ENABLE is allowed with them latched */
#define TLP_FAULT_DIRECTIONAL 0x0300u

#define TLP_CMD_IDENTIFY 0x01u
#define TLP_CMD_IDENTIFY_REQ_LEN 0u
#define TLP_CMD_IDENTIFY_REP_LEN 15u
#define TLP_CMD_GET_PARAM 0x02u
#define TLP_CMD_GET_PARAM_REQ_LEN 2u
#define TLP_CMD_GET_PARAM_REP_LEN 5u
#define TLP_CMD_SET_PARAM 0x03u
#define TLP_CMD_SET_PARAM_REQ_LEN 6u
#define TLP_CMD_SET_PARAM_REP_LEN 5u
#define TLP_CMD_ENABLE 0x04u
#define TLP_CMD_ENABLE_REQ_LEN 2u
#define TLP_CMD_ENABLE_REP_LEN 1u
#define TLP_CMD_MOVE 0x05u
#define TLP_CMD_MOVE_REQ_LEN 6u
#define TLP_CMD_MOVE_REP_LEN 1u
#define TLP_CMD_STOP 0x06u
#define TLP_CMD_STOP_REQ_LEN 1u
#define TLP_CMD_STOP_REP_LEN 1u
#define TLP_CMD_STATUS 0x07u
#define TLP_CMD_STATUS_REQ_LEN 1u
#define TLP_CMD_STATUS_REP_LEN 37u
#define TLP_CMD_TELEMETRY 0x08u
#define TLP_CMD_TELEMETRY_REQ_LEN 2u
#define TLP_CMD_TELEMETRY_REP_LEN 1u
#define TLP_CMD_CLEAR_FAULT 0x09u
#define TLP_CMD_CLEAR_FAULT_REQ_LEN 1u
#define TLP_CMD_CLEAR_FAULT_REP_LEN 5u
#define TLP_CMD_BOOTLOADER 0x0Au
#define TLP_CMD_BOOTLOADER_REQ_LEN 4u
#define TLP_CMD_BOOTLOADER_REP_LEN 1u
#define TLP_CMD_COUNTERS 0x0Bu
#define TLP_CMD_COUNTERS_REQ_LEN 0u
#define TLP_CMD_COUNTERS_REP_LEN 21u
#define TLP_CMD_HEARTBEAT 0x0Cu
#define TLP_CMD_HEARTBEAT_REQ_LEN 0u
#define TLP_CMD_HEARTBEAT_REP_LEN 1u
#define TLP_CMD_HOME 0x0Du
#define TLP_CMD_HOME_REQ_LEN 3u
#define TLP_CMD_HOME_REP_LEN 1u
#define TLP_CMD_SESSION 0x0Eu
#define TLP_CMD_SESSION_REQ_LEN 16u
#define TLP_CMD_SESSION_REP_LEN 33u
#define TLP_CMD_DRIVE 0x0Fu
#define TLP_CMD_DRIVE_REQ_LEN 3u
#define TLP_CMD_DRIVE_REP_LEN 1u
#define TLP_CMD_SAVE 0x10u
#define TLP_CMD_SAVE_REQ_LEN 1u
#define TLP_CMD_SAVE_REP_LEN 7u
/* Command descriptor flags (protocol.toml's command columns). */
#define TLP_CF_SEQ_CHECKED 0x01u
#define TLP_CF_READ_ONLY 0x02u
#define TLP_CF_REPEATABLE 0x04u
#define TLP_CF_UNTAGGED 0x08u
#define TLP_CF_FEEDS_LINK 0x10u
#define TLP_CMD_LIMIT 17u   /* command codes are below this */
/* X(code, handler, req_len, rep_len, flags): one row per command; needing the key
   depends on the payload (open_when): tlp_needs_key() */
#define TLP_COMMAND_TABLE(X) \
    X(TLP_CMD_IDENTIFY, cmd_identify, TLP_CMD_IDENTIFY_REQ_LEN, TLP_CMD_IDENTIFY_REP_LEN, TLP_CF_READ_ONLY | TLP_CF_REPEATABLE | TLP_CF_UNTAGGED) \
    X(TLP_CMD_GET_PARAM, cmd_get_param, TLP_CMD_GET_PARAM_REQ_LEN, TLP_CMD_GET_PARAM_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_READ_ONLY | TLP_CF_REPEATABLE | TLP_CF_UNTAGGED) \
    X(TLP_CMD_SET_PARAM, cmd_set_param, TLP_CMD_SET_PARAM_REQ_LEN, TLP_CMD_SET_PARAM_REP_LEN, TLP_CF_SEQ_CHECKED) \
    X(TLP_CMD_ENABLE, cmd_enable, TLP_CMD_ENABLE_REQ_LEN, TLP_CMD_ENABLE_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_FEEDS_LINK) \
    X(TLP_CMD_MOVE, cmd_move, TLP_CMD_MOVE_REQ_LEN, TLP_CMD_MOVE_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_FEEDS_LINK) \
    X(TLP_CMD_STOP, cmd_stop, TLP_CMD_STOP_REQ_LEN, TLP_CMD_STOP_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_FEEDS_LINK) \
    X(TLP_CMD_STATUS, cmd_status, TLP_CMD_STATUS_REQ_LEN, TLP_CMD_STATUS_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_READ_ONLY | TLP_CF_REPEATABLE | TLP_CF_UNTAGGED) \
    X(TLP_CMD_TELEMETRY, cmd_telemetry, TLP_CMD_TELEMETRY_REQ_LEN, TLP_CMD_TELEMETRY_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_UNTAGGED) \
    X(TLP_CMD_CLEAR_FAULT, cmd_clear_fault, TLP_CMD_CLEAR_FAULT_REQ_LEN, TLP_CMD_CLEAR_FAULT_REP_LEN, TLP_CF_SEQ_CHECKED) \
    X(TLP_CMD_BOOTLOADER, cmd_bootloader, TLP_CMD_BOOTLOADER_REQ_LEN, TLP_CMD_BOOTLOADER_REP_LEN, TLP_CF_SEQ_CHECKED) \
    X(TLP_CMD_COUNTERS, cmd_counters, TLP_CMD_COUNTERS_REQ_LEN, TLP_CMD_COUNTERS_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_READ_ONLY | TLP_CF_REPEATABLE | TLP_CF_UNTAGGED) \
    X(TLP_CMD_HEARTBEAT, cmd_heartbeat, TLP_CMD_HEARTBEAT_REQ_LEN, TLP_CMD_HEARTBEAT_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_REPEATABLE | TLP_CF_FEEDS_LINK) \
    X(TLP_CMD_HOME, cmd_home, TLP_CMD_HOME_REQ_LEN, TLP_CMD_HOME_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_FEEDS_LINK) \
    X(TLP_CMD_SESSION, cmd_session, TLP_CMD_SESSION_REQ_LEN, TLP_CMD_SESSION_REP_LEN, TLP_CF_UNTAGGED) \
    X(TLP_CMD_DRIVE, cmd_drive, TLP_CMD_DRIVE_REQ_LEN, TLP_CMD_DRIVE_REP_LEN, TLP_CF_SEQ_CHECKED | TLP_CF_FEEDS_LINK) \
    X(TLP_CMD_SAVE, cmd_save, TLP_CMD_SAVE_REQ_LEN, TLP_CMD_SAVE_REP_LEN, TLP_CF_SEQ_CHECKED)

#define TLP_MOVE_TRAPEZOID 0x01u
#define TLP_MOVE_UNHOMED 0x80u
#define TLP_HOME_MODE_NEG 0u
#define TLP_HOME_MODE_POS 1u
#define TLP_HOME_MODE_HERE 2u
#define TLP_HOME_STATE_NOT_HOMED 0u
#define TLP_HOME_STATE_HOMING 1u
#define TLP_HOME_STATE_HOMED 2u
#define TLP_LIMIT_NEG 0x01u
#define TLP_LIMIT_POS 0x02u

/* Field offsets in the payloads (little-endian). */
#define TLP_IDENTIFY_REP_STATUS 0u
#define TLP_IDENTIFY_REP_PROTO_VERSION 1u
#define TLP_IDENTIFY_REP_FW_VERSION 2u
#define TLP_IDENTIFY_REP_BUILD_ID 4u
#define TLP_IDENTIFY_REP_AXIS_COUNT 8u
#define TLP_IDENTIFY_REP_LAST_SEQ 9u
#define TLP_IDENTIFY_REP_CLK_HZ 11u
#define TLP_GET_PARAM_REQ_AXIS 0u
#define TLP_GET_PARAM_REQ_PARAM 1u
#define TLP_GET_PARAM_REP_STATUS 0u
#define TLP_GET_PARAM_REP_VALUE 1u
#define TLP_SET_PARAM_REQ_AXIS 0u
#define TLP_SET_PARAM_REQ_PARAM 1u
#define TLP_SET_PARAM_REQ_VALUE 2u
#define TLP_SET_PARAM_REP_STATUS 0u
#define TLP_SET_PARAM_REP_VALUE 1u
#define TLP_ENABLE_REQ_MASK 0u
#define TLP_ENABLE_REQ_ENABLE 1u
#define TLP_ENABLE_REP_STATUS 0u
#define TLP_MOVE_REQ_AXIS 0u
#define TLP_MOVE_REQ_MODE 1u
#define TLP_MOVE_REQ_TARGET 2u
#define TLP_MOVE_REP_STATUS 0u
#define TLP_STOP_REQ_MASK 0u
#define TLP_STOP_REP_STATUS 0u
#define TLP_STATUS_REQ_AXIS 0u
#define TLP_STATUS_REP_STATUS 0u
#define TLP_STATUS_REP_ENABLED 1u
#define TLP_STATUS_REP_FAULTS 2u
#define TLP_STATUS_REP_MOVING 4u
#define TLP_STATUS_REP_HOME 5u
#define TLP_STATUS_REP_LIMITS 6u
#define TLP_STATUS_REP_POSITION 7u
#define TLP_STATUS_REP_SETPOINT 11u
#define TLP_STATUS_REP_VELOCITY_Q8 15u
#define TLP_STATUS_REP_PWM_CMD 19u
#define TLP_STATUS_REP_SAFETY 21u
#define TLP_STATUS_REP_RX_ERRORS 23u
#define TLP_STATUS_REP_LOOP_CYCLES_MAX 25u
#define TLP_STATUS_REP_JITTER_CYCLES_MAX 29u
#define TLP_STATUS_REP_OVERRUNS 33u
#define TLP_TELEMETRY_REQ_EVERY 0u
#define TLP_TELEMETRY_REP_STATUS 0u
#define TLP_CLEAR_FAULT_REQ_MASK 0u
#define TLP_CLEAR_FAULT_REP_STATUS 0u
#define TLP_CLEAR_FAULT_REP_FAULTS0 1u
#define TLP_CLEAR_FAULT_REP_FAULTS1 3u
#define TLP_BOOTLOADER_REQ_MAGIC 0u
#define TLP_BOOTLOADER_REP_STATUS 0u
#define TLP_COUNTERS_REP_STATUS 0u
#define TLP_COUNTERS_REP_FRAMES_OK 1u
#define TLP_COUNTERS_REP_CRC 3u
#define TLP_COUNTERS_REP_FRAMING 5u
#define TLP_COUNTERS_REP_LENGTH 7u
#define TLP_COUNTERS_REP_OVERSIZE 9u
#define TLP_COUNTERS_REP_UNKNOWN 11u
#define TLP_COUNTERS_REP_REPLAY 13u
#define TLP_COUNTERS_REP_REJECTED 15u
#define TLP_COUNTERS_REP_TX_DROPPED 17u
#define TLP_COUNTERS_REP_AUTH 19u
#define TLP_HEARTBEAT_REP_STATUS 0u
#define TLP_HOME_REQ_AXIS 0u
#define TLP_HOME_REQ_MODE 1u
#define TLP_HOME_REQ_INDEX 2u
#define TLP_HOME_REP_STATUS 0u
#define TLP_SESSION_REQ_HOST_NONCE 0u
#define TLP_SESSION_REP_STATUS 0u
#define TLP_SESSION_REP_BOARD_NONCE 1u
#define TLP_SESSION_REP_PROOF 17u
#define TLP_DRIVE_REQ_AXIS 0u
#define TLP_DRIVE_REQ_DUTY 1u
#define TLP_DRIVE_REP_STATUS 0u
#define TLP_SAVE_REQ_OP 0u
#define TLP_SAVE_REP_STATUS 0u
#define TLP_SAVE_REP_SAVED 1u
#define TLP_SAVE_REP_DIFFERS 2u
#define TLP_SAVE_REP_SEQ 3u
#define TLP_TELEM_TIME_US 0u
#define TLP_TELEM_HEAD_LEN 4u
#define TLP_TELEM_AX_SETPOINT 0u
#define TLP_TELEM_AX_POSITION 4u
#define TLP_TELEM_AX_VELOCITY_Q8 8u
#define TLP_TELEM_AX_ERROR 12u
#define TLP_TELEM_AX_PWM_CMD 16u
#define TLP_TELEM_AX_FAULTS 18u
#define TLP_TELEM_AX_ENABLED 20u
#define TLP_TELEM_AX_LEN 21u
#define TLP_TELEM_LEN 46u

/* Authentication ([auth] of protocol.toml; docs/security.md). */
#define TLP_AUTH_KEY_BYTES 32u
#define TLP_AUTH_TAG_BYTES 16u
#define TLP_AUTH_UPLOAD_TAG_BYTES 32u
#define TLP_AUTH_NONCE_BYTES 16u
#define TLP_AUTH_SESSION_WINDOW 32768u
#define TLP_AUTH_LABEL_FRAME "TLCF"
#define TLP_AUTH_LABEL_PROOF "TLSP"
#define TLP_AUTH_LABEL_NONCE "TLNG"
#define TLP_AUTH_LABEL_UPLOAD "TLUP"
#define TLP_AUTH_LABEL_CHECK "TLKC"
#define TLP_AUTH_KEY_SLOT_BYTES 64u
#define TLP_AUTH_KEY_SLOT_MAGIC 0x594B4C54u
#define TLP_AUTH_KEY_SLOT_ALGORITHM 1u
#define TLP_AUTH_LABEL_BYTES 4u
/* 1 if cmd with this request payload needs the key (auth = "key" and no open_when match). */
static inline int tlp_needs_key(uint8_t cmd, const uint8_t *payload)
{
    (void)payload;
    switch (cmd) {
    case TLP_CMD_SET_PARAM: return 1;
    case TLP_CMD_ENABLE: return !(payload[TLP_ENABLE_REQ_ENABLE] == 0u);
    case TLP_CMD_MOVE: return 1;
    case TLP_CMD_CLEAR_FAULT: return 1;
    case TLP_CMD_BOOTLOADER: return 1;
    case TLP_CMD_HEARTBEAT: return 1;
    case TLP_CMD_HOME: return 1;
    case TLP_CMD_DRIVE: return 1;
    case TLP_CMD_SAVE: return !(payload[TLP_SAVE_REQ_OP] == 0u);
    default: return 0;   /* open, or unknown (answered UNKNOWN_CMD) */
    }
}

/* Parameter store ([store] of protocol.toml; docs/firmware.md). */
#define TLP_STORE_MAGIC 0x54534C54u
#define TLP_STORE_SLOT_A 0x7E0000u
#define TLP_STORE_SLOT_B 0x7F0000u
#define TLP_STORE_FLASH_BYTES 0x800000u
#define TLP_STORE_SECTOR_BYTES 0x10000u
#define TLP_STORE_PAGE_BYTES 0x100u
#define TLP_STORE_OP_READ 0x3u
#define TLP_STORE_OP_WRITE_ENABLE 0x6u
#define TLP_STORE_OP_READ_STATUS 0x5u
#define TLP_STORE_OP_PAGE_PROGRAM 0x2u
#define TLP_STORE_OP_SECTOR_ERASE 0xD8u
#define TLP_STORE_STATUS_WIP 0x1u
#define TLP_STORE_STATUS_WEL 0x2u
#define TLP_STORE_PAGE_PROGRAM_US 0x1388u
#define TLP_STORE_SECTOR_ERASE_US 0x2DC6C0u

#define TLP_GLOBAL_AXIS 0xFFu
#define TLP_P_LAW 0u
#define TLP_P_KP_Q16 1u
#define TLP_P_KD_Q16 2u
#define TLP_P_KI_Q16 3u
#define TLP_P_KP_UNM_RAD 4u
#define TLP_P_KD_UNMS_RAD 5u
#define TLP_P_KI_UNM_RADS 6u
#define TLP_P_TAU_MAX_MNM 7u
#define TLP_P_COUNTS_PER_REV 8u
#define TLP_P_PITCH_UM 9u
#define TLP_P_CMD_LIMIT 10u
#define TLP_P_PW0 11u
#define TLP_P_PWMAX 12u
#define TLP_P_FDIV 13u
#define TLP_P_DEADBAND_Q16 14u
#define TLP_P_FOLLOW_LIMIT 15u
#define TLP_P_SOFT_MIN 16u
#define TLP_P_SOFT_MAX 17u
#define TLP_P_VMAX 18u
#define TLP_P_AMAX 19u
#define TLP_P_VEL_MODE 20u
#define TLP_P_BRAKE 21u
#define TLP_P_STALL_CMD 22u
#define TLP_P_STALL_MS 23u
#define TLP_P_LIMIT_SW 24u
#define TLP_P_HOME_VEL 25u
#define TLP_P_HOME_POS 26u
#define TLP_P_ENC_CMD0 27u
#define TLP_P_ENC_CPS 28u
#define TLP_P_ENC_TAU_MS 29u
#define TLP_P_ENC_SLACK 30u
#define TLP_P_PERIOD_US 64u
#define TLP_P_LINK_TIMEOUT_MS 65u
#define TLP_P_BAUD_DIV 66u
#define TLP_P_PWM_MAX_HZ 67u
#define TLP_P_FC_POS 31u
#define TLP_P_FC_NEG 32u
#define TLP_P_IZONE_Q16 33u
#define TLP_P_KVFF_Q16 34u
#define TLP_P_DITHER_AMP 35u
#define TLP_P_DITHER_HALF 36u
#define TLP_P_KAFF_Q16 37u

#define TLP_AXIS_COUNT 2u
/* dflt[axis]: a global parameter's default is dflt[0]; tighten: +1 / -1 = while an axis is
   enabled the value may only rise / fall (a safety limit), 0 = free */
typedef struct { uint8_t id; uint8_t global; int8_t tighten; int32_t min; int32_t max; int32_t dflt[TLP_AXIS_COUNT]; } tlp_param_info_t;
#define TLP_PARAM_COUNT 42u
#define TLP_PARAM_LAYOUT 0xB34978A2u   /* the stored record's layout word ([store]) */
static const tlp_param_info_t TLP_PARAM_INFO[TLP_PARAM_COUNT] = {
    {0u, 0u, 0, 0L, 3L, {1L, 1L}},  /* LAW */
    {1u, 0u, 0, 0L, 2147483647L, {17134L, 23145L}},  /* KP_Q16 */
    {2u, 0u, 0, 0L, 2147483647L, {0L, 0L}},  /* KD_Q16 */
    {3u, 0u, 0, 0L, 2147483647L, {0L, 0L}},  /* KI_Q16 */
    {4u, 0u, 0, 0L, 100000000L, {820000L, 960000L}},  /* KP_UNM_RAD */
    {5u, 0u, 0, 0L, 100000000L, {0L, 0L}},  /* KD_UNMS_RAD */
    {6u, 0u, 0, 0L, 100000000L, {0L, 0L}},  /* KI_UNM_RADS */
    {7u, 0u, 0, 1L, 1000000L, {2400L, 2080L}},  /* TAU_MAX_MNM */
    {8u, 0u, 0, 1L, 1000000L, {8400L, 8400L}},  /* COUNTS_PER_REV */
    {9u, 0u, 0, 1L, 1000000L, {4000L, 4000L}},  /* PITCH_UM */
    {10u, 0u, -1, 0L, 1023L, {1023L, 1023L}},  /* CMD_LIMIT */
    {11u, 0u, -1, 0L, 1023L, {0L, 0L}},  /* PW0 */
    {12u, 0u, -1, 0L, 1023L, {1023L, 1023L}},  /* PWMAX */
    {13u, 0u, 1, 1L, 65535L, {109L, 244L}},  /* FDIV */
    {14u, 0u, 0, 0L, 2147483647L, {32768L, 32768L}},  /* DEADBAND_Q16 */
    {15u, 0u, -1, 1L, 2147483647L, {16800L, 16800L}},  /* FOLLOW_LIMIT */
    {16u, 0u, 1, (-2147483647L), 2147483647L, {(-1000000L), (-1000000L)}},  /* SOFT_MIN */
    {17u, 0u, -1, (-2147483647L), 2147483647L, {1000000L, 1000000L}},  /* SOFT_MAX */
    {18u, 0u, 0, 1L, 10000000L, {8400L, 8400L}},  /* VMAX */
    {19u, 0u, 0, 1L, 100000000L, {16800L, 16800L}},  /* AMAX */
    {20u, 0u, 0, 0L, 1L, {1L, 1L}},  /* VEL_MODE */
    {21u, 0u, 0, 0L, 1L, {1L, 1L}},  /* BRAKE */
    {22u, 0u, -1, 1L, 1023L, {100L, 100L}},  /* STALL_CMD */
    {23u, 0u, -1, 10L, 10000L, {500L, 500L}},  /* STALL_MS */
    {24u, 0u, 1, 0L, 1L, {1L, 1L}},  /* LIMIT_SW */
    {25u, 0u, 0, 1L, 1000000L, {2100L, 2100L}},  /* HOME_VEL */
    {26u, 0u, 0, (-2147483647L), 2147483647L, {0L, 0L}},  /* HOME_POS */
    {27u, 0u, -1, 0L, 1023L, {64L, 64L}},  /* ENC_CMD0 */
    {28u, 0u, 1, 1L, 10000000L, {23416L, 17338L}},  /* ENC_CPS */
    {29u, 0u, -1, 1L, 60000L, {600L, 1600L}},  /* ENC_TAU_MS */
    {30u, 0u, -1, 1L, 1000000L, {64L, 64L}},  /* ENC_SLACK */
    {64u, 1u, 0, 50L, 25000L, {25000L, 25000L}},  /* PERIOD_US */
    {65u, 1u, -1, 10L, 60000L, {500L, 500L}},  /* LINK_TIMEOUT_MS */
    {66u, 1u, 0, 15L, 65535L, {433L, 433L}},  /* BAUD_DIV */
    {67u, 1u, -1, 1L, 25000L, {25000L, 25000L}},  /* PWM_MAX_HZ */
    {31u, 0u, 0, 0L, 1023L, {0L, 0L}},  /* FC_POS */
    {32u, 0u, 0, 0L, 1023L, {0L, 0L}},  /* FC_NEG */
    {33u, 0u, 0, 0L, 2147483647L, {0L, 0L}},  /* IZONE_Q16 */
    {34u, 0u, 0, 0L, 16777215L, {0L, 0L}},  /* KVFF_Q16 */
    {35u, 0u, 0, 0L, 1023L, {0L, 0L}},  /* DITHER_AMP */
    {36u, 0u, 0, 1L, 65535L, {1L, 1L}},  /* DITHER_HALF */
    {37u, 0u, 0, 0L, 16777215L, {0L, 0L}},  /* KAFF_Q16 */
};
/* parameter id -> index into TLP_PARAM_INFO, -1: no such parameter */
static const int8_t TLP_PARAM_INDEX[256] = {
     0,  1,  2,  3,  4,  5,  6,  7,  8,  9, 10, 11, 12, 13, 14, 15,
    16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 35,
    36, 37, 38, 39, 40, 41, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    31, 32, 33, 34, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
};

#endif
