/*
 * mavconform's golden vectors checked with the MAVLink C library that pymavlink's mavgen
 * generates from the dialect XML (what PX4 and ArduPilot build on), compiled by the test
 * with the system compiler. tools/vectors_crosscheck.py writes the two headers it includes:
 *   dialect.h  #include "<dialect>/mavlink.h"
 *   glue.h     per message: mavlink_msg_X_decode, the fields as JSON, mavlink_msg_X_encode_chan
 *
 * stdin: one vector per line, "ID SIGNED HEX"; argv[1]: the test key (64 hex digits).
 * stdout: one JSON object per vector, the result format of vectors/verify.py.
 *
 * Decoding is mavlink_frame_char() byte by byte on a fresh channel (with the test key in
 * the channel's signing struct for signed vectors); a rejection is named from what the
 * library reports: MAVLINK_FRAMING_BAD_CRC (bad_crc, or unknown_msgid when the library's
 * CRC_EXTRA table has no entry for the id), MAVLINK_FRAMING_BAD_SIGNATURE, a parse error
 * in state GOT_LENGTH (the incompat flags byte: unknown_incompat_flags) or elsewhere
 * (bad_length, with MAVLINK_CHECK_MESSAGE_LENGTH), or a frame still incomplete when the
 * bytes end (bad_length). Re-encoding is the generated mavlink_msg_X_encode_chan() on a
 * second channel set to the vector's sequence number, version and signature block.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dialect.h"

/* --- a tiny JSON writer ------------------------------------------------------------- */
static char jbuf[1 << 16];
static size_t jlen;
static int jfirst[16];
static int jdepth;

static void j_raw(const char *s) {
    size_t n = strlen(s);
    if (jlen + n < sizeof jbuf) {
        memcpy(jbuf + jlen, s, n);
        jlen += n;
    }
}
static void j_sep(void) {
    if (!jfirst[jdepth]) j_raw(",");
    jfirst[jdepth] = 0;
}
static void j_open(const char *bracket) {
    j_raw(bracket);
    jfirst[++jdepth] = 1;
}
static void j_close(const char *bracket) {
    j_raw(bracket);
    jdepth--;
}
static void j_key(const char *name) {
    j_sep();
    j_raw("\"");
    j_raw(name);
    j_raw("\":");
    jfirst[jdepth + 1] = 1;
}
static void j_elem(void) { j_sep(); }
static void j_uint(unsigned long long v) {
    char t[32];
    snprintf(t, sizeof t, "%llu", v);
    j_raw(t);
}
static void j_int(long long v) {
    char t[32];
    snprintf(t, sizeof t, "%lld", v);
    j_raw(t);
}
static void j_float(double v, int single) {
    char t[40];
    if (isnan(v)) {
        j_raw("\"NaN\"");
        return;
    }
    if (isinf(v)) {
        j_raw(v > 0 ? "\"Infinity\"" : "\"-Infinity\"");
        return;
    }
    snprintf(t, sizeof t, single ? "%.9g" : "%.17g", v);
    if (!strpbrk(t, ".e")) strcat(t, ".0"); /* stay a float: -0 must read as -0.0 */
    j_raw(t);
}
static void j_str(const char *s, size_t max) {
    char t[8];
    j_raw("\"");
    for (size_t i = 0; i < max && s[i]; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c == '"' || c == '\\' || c < 0x20 || c > 0x7e) {
            snprintf(t, sizeof t, "\\u%04x", c);
            j_raw(t);
        } else {
            t[0] = (char)c;
            t[1] = 0;
            j_raw(t);
        }
    }
    j_raw("\"");
}
static void j_text(const char *key, const char *value) {
    j_key(key);
    j_str(value, strlen(value));
}

#define J_U(name, v) (j_key(name), j_uint((unsigned long long)(v)))
#define J_I(name, v) (j_key(name), j_int((long long)(v)))
#define J_F(name, v, single) (j_key(name), j_float((double)(v), single))
#define J_S(name, v, n) (j_key(name), j_str((v), (n)))

/* decode_fields_encode(): the generated per-message switch (1: known message) */
#include "glue.h"

static int unhex(const char *s, uint8_t *out, size_t cap) {
    size_t n = strlen(s);
    if (n % 2 || n / 2 > cap) return -1;
    for (size_t i = 0; i < n / 2; i++) {
        unsigned v;
        if (sscanf(s + 2 * i, "%2x", &v) != 1) return -1;
        out[i] = (uint8_t)v;
    }
    return (int)(n / 2);
}

static void refused(const char *id, const char *kind, const char *detail) {
    jlen = 0;
    jdepth = 0;
    jfirst[0] = 1;
    j_open("{");
    j_text("id", id);
    j_key("ok");
    j_raw("false");
    j_text("error", kind);
    j_text("detail", detail);
    j_close("}");
    jbuf[jlen] = 0;
    puts(jbuf);
}

int main(int argc, char **argv) {
    static char line[4096];
    uint8_t key[32], data[1024];
    static mavlink_signing_t in_signing, out_signing;
    static mavlink_signing_streams_t streams;
    if (argc != 2 || unhex(argv[1], key, sizeof key) != 32) {
        fprintf(stderr, "usage: harness KEYHEX < vectors\n");
        return 2;
    }
    while (fgets(line, sizeof line, stdin)) {
        char id[256], hex[2100], detail[160];
        int is_signed;
        if (sscanf(line, "%255s %d %2099s", id, &is_signed, hex) != 3) continue;
        int n = unhex(hex, data, sizeof data);
        if (n < 0) {
            fprintf(stderr, "harness: bad hex for %s\n", id);
            return 2;
        }
        mavlink_status_t *st = mavlink_get_channel_status(MAVLINK_COMM_0);
        memset(st, 0, sizeof *st);
        memset(mavlink_get_channel_buffer(MAVLINK_COMM_0), 0, sizeof(mavlink_message_t));
        if (is_signed) {
            memset(&in_signing, 0, sizeof in_signing);
            memcpy(in_signing.secret_key, key, 32);
            memset(&streams, 0, sizeof streams);
            st->signing = &in_signing;
            st->signing_streams = &streams;
        }
        mavlink_message_t msg, out;
        mavlink_status_t copy;
        int result = -1, at = 0;
        const char *why = NULL;
        for (int i = 0; i < n; i++) {
            uint8_t state = st->parse_state;
            uint8_t r = mavlink_frame_char(MAVLINK_COMM_0, data[i], &msg, &copy);
            if (r != MAVLINK_FRAMING_INCOMPLETE) {
                result = r;
                at = i + 1;
                break;
            }
            /* the library zeroes parse_error after every byte and reports it in the status
               copy's packet_rx_drop_count */
            if (copy.packet_rx_drop_count != 0) {
                why = state == MAVLINK_PARSE_STATE_GOT_LENGTH ? "unknown_incompat_flags" : "bad_length";
                snprintf(detail, sizeof detail, "parse error at byte %d in parse state %d", i, state);
                break;
            }
        }
        if (why) {
            refused(id, why, detail);
            continue;
        }
        if (result < 0) {
            snprintf(detail, sizeof detail, "no frame when the bytes ended (parse state %d)", st->parse_state);
            refused(id, st->parse_state != MAVLINK_PARSE_STATE_IDLE ? "bad_length" : "other", detail);
            continue;
        }
        if (result == MAVLINK_FRAMING_BAD_CRC) {
            int known = mavlink_get_msg_entry(msg.msgid) != NULL;
            snprintf(detail, sizeof detail, "MAVLINK_FRAMING_BAD_CRC%s",
                     known ? "" : "; no CRC_EXTRA entry for the message id");
            refused(id, known ? "bad_crc" : "unknown_msgid", detail);
            continue;
        }
        if (result == MAVLINK_FRAMING_BAD_SIGNATURE) {
            refused(id, "bad_signature", "MAVLINK_FRAMING_BAD_SIGNATURE");
            continue;
        }
        if (at != n) {
            snprintf(detail, sizeof detail, "%d bytes after the frame", n - at);
            refused(id, "other", detail);
            continue;
        }
        /* re-encode on channel 1, with the frame's sequence number, version and signature block */
        mavlink_status_t *os = mavlink_get_channel_status(MAVLINK_COMM_1);
        memset(os, 0, sizeof *os);
        os->current_tx_seq = msg.seq;
        if (msg.magic == MAVLINK_STX_MAVLINK1) os->flags |= MAVLINK_STATUS_FLAG_OUT_MAVLINK1;
        uint64_t timestamp = 0;
        int signed_frame = (msg.incompat_flags & MAVLINK_IFLAG_SIGNED) != 0;
        if (signed_frame) {
            for (int b = 6; b >= 1; b--) timestamp = timestamp << 8 | msg.signature[b];
            memset(&out_signing, 0, sizeof out_signing);
            memcpy(out_signing.secret_key, key, 32);
            out_signing.link_id = msg.signature[0];
            out_signing.timestamp = timestamp;
            out_signing.flags = MAVLINK_SIGNING_FLAG_SIGN_OUTGOING;
            os->signing = &out_signing;
        }
        jlen = 0;
        jdepth = 0;
        jfirst[0] = 1;
        j_open("{");
        j_text("id", id);
        j_key("ok");
        j_raw("true");
        J_U("msgid", msg.msgid);
        J_U("sysid", msg.sysid);
        J_U("compid", msg.compid);
        J_U("seq", msg.seq);
        j_key("signature");
        if (signed_frame) {
            j_open("{");
            J_U("link_id", msg.signature[0]);
            J_U("timestamp", timestamp);
            j_close("}");
        } else {
            j_raw("null");
        }
        j_key("fields");
        j_open("{");
        int known = decode_fields_encode(&msg, MAVLINK_COMM_1, &out);
        j_close("}");
        if (!known) {
            snprintf(detail, sizeof detail, "message id %u has no decoder", (unsigned)msg.msgid);
            refused(id, "unknown_msgid", detail);
            continue;
        }
        uint8_t wire[MAVLINK_MAX_PACKET_LEN];
        uint16_t len = mavlink_msg_to_send_buffer(wire, &out);
        j_key("reencoded");
        j_raw("\"");
        for (uint16_t b = 0; b < len; b++) {
            char t[3];
            snprintf(t, sizeof t, "%02x", wire[b]);
            j_raw(t);
        }
        j_raw("\"");
        j_close("}");
        jbuf[jlen] = 0;
        puts(jbuf);
    }
    return 0;
}
