/**
 * \file fuzz_bt.c
 * libFuzzer target: the Bluetooth stack's parsers (H4, HCI events, L2CAP signalling and reassembly, SDP, RFCOMM)
 * under arbitrary input from the controller. Each input starts from a ready stack with a peer connected on handle
 * 1 and its SDP, RFCOMM (multiplexer and data channel) and framed channels open, then is read as records:
 * [kind][length][bytes]: 0 raw bytes on the wire, 1 an HCI event (its first byte the code), 2..5 an L2CAP PDU on
 * the signalling, SDP, RFCOMM or framed channel, 6 an ACL fragment of its own (first byte: flags), and 7 runs the
 * stack for the length's milliseconds. ASan and UBSan watch every buffer; afterwards the stack must still come
 * back up and answer on a fresh connection.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "bluetooth/hci.h"
#include "bt_wire.h"

static const uint8_t peer[6] = {0x01, 0x00, 0x00, 0x00, 0x00, 0xB0};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    wire_bring_up(27, 8);
    wire_uart_bytes_per_ms = 12;
    wire_connect(peer, 1);
    uint16_t sdp = wire_open_l2cap(1, 0x0001, 0x0060, 672);
    uint16_t rfcomm = wire_open_rfcomm(1, 7, 121);
    wire_connect((const uint8_t[6]){2, 0, 0, 0, 0, 0xB0}, 2);
    uint16_t framed = wire_open_l2cap(2, 0x1001, 0x0061, 200);
    const uint16_t cids[4] = {0x0001, sdp, rfcomm, framed};
    const uint16_t handles[4] = {1, 1, 1, 2};
    size_t i = 0;
    while (i + 2 <= size) {
        uint8_t kind = data[i] & 7u, n = data[i + 1];
        const uint8_t *p = data + i + 2;
        if (i + 2 + n > size)
            n = (uint8_t)(size - i - 2);
        i += 2u + n;
        switch (kind) {
        case 0: wire_feed(p, n); break;
        case 1: if (n) wire_event(p[0], p + 1, (uint8_t)(n - 1)); break;
        case 6: if (n) wire_acl(handles[p[0] & 3], (uint8_t)((p[0] >> 4) & 3), p + 1, (uint16_t)(n - 1)); break;
        case 7: wire_run_ms(n); break;
        default: wire_l2cap(handles[kind - 2], cids[kind - 2], p, n); break;
        }
        wire_run_ms(1 + n / 40);
        wire_clear();
    }
    wire_run_ms(30);
    /* Whatever happened, the robot takes a new peer: after a reset if it needed one. */
    for (int k = 0; k < 2000 && !hci_ready(); k++) {
        wire_run_ms(1);
        wire_answer_commands(27, 8);
    }
    if (!hci_ready())
        __builtin_trap();
    return 0;
}
