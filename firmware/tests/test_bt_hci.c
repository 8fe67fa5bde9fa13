#include <string.h>

#include "bluetooth/h4.h"
#include "bluetooth/hci.h"
#include "bt_wire.h"
#include "core/data.h"
#include "drivers/eeprom.h"
#include "harness.h"

static const uint8_t phone[6] = {0x01, 0x00, 0x00, 0x00, 0x00, 0xB0};
static const uint8_t laptop[6] = {0x02, 0x00, 0x00, 0x00, 0x00, 0xB0};
static const uint8_t tablet[6] = {0x03, 0x00, 0x00, 0x00, 0x00, 0xB0};

static void initialises_the_controller_in_order(void)
{
    wire_reset();
    static const uint16_t order[] = {0x0C03, 0x1005, 0x1009, 0x0C33, 0x0C01, 0x0C56, 0x0C13, 0x0C24, 0x0C1A};
    for (int i = 0; i < 30 && !hci_ready(); i++) {
        wire_run_ms(1);
        wire_answer_commands(27, 64);
    }
    CHECK(hci_ready(), "not ready");
    int k = 0;
    for (int i = 0; i < wire_out_count; i++)
        if (wire_out[i].type == H4_COMMAND) {
            CHECK(k < 9 && wire_out[i].opcode == order[k], "command %d: %04x", k, wire_out[i].opcode);
            k++;
        }
    CHECK(k == 9, "%d commands", k);
    const wire_packet_t *c = wire_find_command(0x0C33, 0);
    CHECK(c && c->len == 7 && (c->data[0] | c->data[1] << 8) == BT_ACL_RX_MAX, "host buffer size");
    c = wire_find_command(0x0C13, 0);
    CHECK(c && c->len == 248 && memcmp(c->data, "PocketBot-7\0", 12) == 0, "local name %.20s", c ? (char *)c->data : "");
    c = wire_find_command(0x0C24, 0);
    CHECK(c && c->data[0] == 0x04 && c->data[1] == 0x08 && c->data[2] == 0x00, "class of device");
    c = wire_find_command(0x0C56, 0);
    CHECK(c && c->data[0] == 1, "simple pairing mode");
    c = wire_find_command(0x0C1A, 0);
    CHECK(c && c->data[0] == 3, "scan enable");
    const uint8_t *a = hci_bd_addr();
    CHECK(a[0] == 0x0F && a[5] == 0x0A, "address");
    CHECK(robot_state.errors.bt_resets == 0, "a reset counted at power-up");
}

static void accepts_two_links_and_refuses_a_third(void)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    wire_connect(laptop, 2);
    const wire_packet_t *c = wire_find_command(0x0409, 0);
    CHECK(c && memcmp(c->data, phone, 6) == 0 && c->data[6] == 0x01, "accept: stays peripheral");
    CHECK(hci_link_addr(0) && memcmp(hci_link_addr(0), phone, 6) == 0, "link 0");
    CHECK(hci_link_addr(1) && memcmp(hci_link_addr(1), laptop, 6) == 0, "link 1");
    uint8_t req[10] = {0};
    memcpy(req, tablet, 6);
    req[9] = 1;
    wire_event(0x04, req, 10);
    wire_run_ms(1);
    c = wire_find_command(0x040A, 0);
    CHECK(c && memcmp(c->data, tablet, 6) == 0 && c->data[6] == 0x0D, "third link not refused");
    uint8_t gone[4] = {0, 1, 0, 0x13};
    wire_event(0x05, gone, 4);
    wire_run_ms(1);
    CHECK(hci_link_addr(0) == NULL, "link 0 still up");
    wire_connect(tablet, 3);
    CHECK(hci_link_addr(0) && memcmp(hci_link_addr(0), tablet, 6) == 0, "the freed link not reused");
}

/* The controller asks for a link key, then pairs: the key it notifies is the one it gets next time. */
static void pairs_just_works_and_remembers_the_key_in_eeprom(void)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    wire_event(0x17, phone, 6); /* Link_Key_Request: none yet */
    wire_run_ms(1);
    CHECK(wire_find_command(0x040C, 0), "no negative link key reply");
    wire_answer_commands(27, 64);
    wire_event(0x31, phone, 6); /* IO_Capability_Request */
    wire_run_ms(1);
    const wire_packet_t *c = wire_find_command(0x042B, 0);
    CHECK(c && c->data[6] == 0x03 && c->data[7] == 0 && c->data[8] == 0x04, "IO capability reply");
    wire_answer_commands(27, 64);
    uint8_t confirm[10];
    memcpy(confirm, phone, 6);
    memset(confirm + 6, 0x11, 4);
    wire_event(0x33, confirm, 10); /* User_Confirmation_Request */
    wire_run_ms(1);
    CHECK(wire_find_command(0x042C, 0), "no user confirmation reply");
    wire_answer_commands(27, 64);
    uint8_t note[23];
    memcpy(note, phone, 6);
    for (int i = 0; i < 16; i++)
        note[6 + i] = (uint8_t)(0xA0 + i);
    note[22] = 0x04;
    wire_event(0x18, note, 23); /* Link_Key_Notification */
    wire_run_ms(3);
    uint8_t rec[32];
    eeprom_read(HCI_KEYS_EEPROM_ADDR, rec, 32);
    CHECK(memcmp(rec + 1, phone, 6) == 0 && memcmp(rec + 7, note + 6, 16) == 0, "key not in EEPROM");
    eeprom_read(0, rec, 32);
    CHECK(rec[0] == 0xFF, "the settings image's place written");

    hci_init(); /* a reset of the robot: the EEPROM stays */
    for (int i = 0; i < 30 && !hci_ready(); i++) {
        wire_run_ms(1);
        wire_answer_commands(27, 64);
    }
    wire_connect(phone, 1);
    wire_clear();
    wire_event(0x17, phone, 6);
    wire_run_ms(1);
    c = wire_find_command(0x040B, 0);
    CHECK(c && c->len == 22 && memcmp(c->data + 6, note + 6, 16) == 0, "the stored key not given");
}

static void the_oldest_key_gives_way(void)
{
    wire_bring_up(27, 64);
    uint8_t note[23] = {0};
    for (int k = 0; k < (int)HCI_KEYS + 1; k++) {
        note[0] = (uint8_t)(0x10 + k);
        note[6] = (uint8_t)k;
        wire_event(0x18, note, 23);
        wire_run_ms(2);
    }
    int found_first = 0, found_last = 0;
    for (unsigned s = 0; s < HCI_KEYS; s++) {
        uint8_t rec[32];
        eeprom_read((uint16_t)(HCI_KEYS_EEPROM_ADDR + s * 32), rec, 32);
        found_first += rec[1] == 0x10;
        found_last += rec[1] == 0x10 + HCI_KEYS && rec[7] == HCI_KEYS;
    }
    CHECK(!found_first && found_last == 1, "oldest kept %d, newest stored %d", found_first, found_last);
}

/* The phone's framed channel was reported lost; the controller is reset and initialised again (its wire quiet for
 * two ticks first), and accepts the phone's link again. */
static void phone_lost_then_accepted_again(void)
{
    CHECK(wire_up.framed_closed[0] == 1 && wire_up.framed_lost[0] == 1, "link loss not reported");
    wire_run_ms(3);
    CHECK(wire_find_command(0x0C03, 0), "no reset sent");
    for (int i = 0; i < 30 && !hci_ready(); i++) {
        wire_run_ms(1);
        wire_answer_commands(27, 64);
    }
    CHECK(hci_ready(), "not back");
    wire_connect(phone, 1);
    CHECK(hci_link_addr(0) != NULL, "link not accepted again");
}

static void a_command_unanswered_resets_the_controller_and_drops_the_links(void)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    wire_open_l2cap(1, BT_PSM_FRAMED, 0x0041, 200);
    CHECK(wire_up.framed_opened[0] == 1, "framed channel not open");
    wire_clear();
    wire_run_ms(HCI_KEEPALIVE_MS); /* the keep-alive goes out and nobody answers */
    CHECK(wire_find_command(0x0C19, 0), "no keep-alive");
    wire_run_ms(HCI_COMMAND_TIMEOUT_MS + 5);
    CHECK(robot_state.errors.bt_timeouts == 1 && robot_state.errors.bt_resets == 1, "timeouts %u resets %u",
          robot_state.errors.bt_timeouts, robot_state.errors.bt_resets);
    phone_lost_then_accepted_again();
}

/* A controller power-cycled behind the stack's back (its UART wire kept) answers commands as before but has
 * forgotten the links and the scans: the keep-alive (Read_Scan_Enable) finds the scans off and resets it. */
static void a_controller_power_cycled_unnoticed_is_found_by_the_keep_alive(void)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    wire_open_l2cap(1, BT_PSM_FRAMED, 0x0041, 200);
    wire_clear();
    const uint8_t scans_on = 0x03, scans_off = 0x00;
    wire_run_ms(HCI_KEEPALIVE_MS);
    CHECK(wire_find_command(0x0C19, 0), "no keep-alive");
    wire_command_complete(0x0C19, &scans_on, 1);
    wire_run_ms(HCI_KEEPALIVE_MS);
    CHECK(wire_find_command(0x0C19, 1), "no second keep-alive");
    const uint8_t unknown[4] = {1, 0x19, 0x0C, 0x01}; /* a controller without the command: Unknown HCI Command */
    wire_event(0x0E, unknown, 4);
    wire_run_ms(HCI_KEEPALIVE_MS);
    CHECK(robot_state.errors.bt_resets == 0 && hci_link_addr(0) != NULL, "a sound controller reset");
    CHECK(wire_find_command(0x0C19, 2), "no third keep-alive");
    wire_command_complete(0x0C19, &scans_off, 1);
    wire_run_ms(1);
    CHECK(robot_state.errors.bt_resets == 1 && robot_state.errors.bt_timeouts == 0, "timeouts %u resets %u",
          robot_state.errors.bt_timeouts, robot_state.errors.bt_resets);
    phone_lost_then_accepted_again();
}

/* A Command Complete that grants no command credit (Num_HCI_Command_Packets 0) and no credit after it: the stack
 * cannot send, so after the command timeout it resets the controller as for a command unanswered. */
static void no_command_credit_for_long_resets_the_controller(void)
{
    wire_bring_up(27, 64);
    wire_clear();
    const uint8_t none[3] = {0, 0x00, 0x00}; /* no credit, opcode 0 (no command) */
    wire_event(0x0E, none, 3);
    wire_run_ms(HCI_COMMAND_TIMEOUT_MS + 5);
    CHECK(robot_state.errors.bt_timeouts == 1 && robot_state.errors.bt_resets == 1, "timeouts %u resets %u",
          robot_state.errors.bt_timeouts, robot_state.errors.bt_resets);
    CHECK(wire_find_command(0x0C03, 0), "no reset sent");
    for (int i = 0; i < 30 && !hci_ready(); i++) {
        wire_run_ms(1);
        wire_answer_commands(27, 64);
    }
    CHECK(hci_ready(), "not back");
}

static void a_garbage_burst_is_counted_and_survived(void)
{
    wire_bring_up(27, 64);
    wire_connect(phone, 1);
    uint8_t junk[300];
    uint32_t x = 12345;
    for (unsigned i = 0; i < sizeof junk; i++) {
        x = x * 1103515245u + 12345u;
        junk[i] = (uint8_t)(x >> 16);
    }
    junk[0] = 0x77; /* not a packet type */
    wire_feed(junk, 200);
    wire_run_ms(1);
    wire_feed(junk + 200, 100); /* still arriving */
    wire_run_ms(1);
    CHECK(robot_state.errors.bt_wire >= 1 && robot_state.errors.bt_resets >= 1, "wire %u resets %u",
          robot_state.errors.bt_wire, robot_state.errors.bt_resets);
    CHECK(hci_link_addr(0) == NULL, "link kept across a reset");
    for (int i = 0; i < 40 && !hci_ready(); i++) {
        wire_run_ms(1);
        wire_answer_commands(27, 64);
    }
    CHECK(hci_ready(), "not back after the burst");
}

static void a_lost_byte_stalls_a_packet_and_resets(void)
{
    wire_bring_up(27, 64);
    const uint8_t cut[] = {H4_EVENT, 0x13, 5, 1, 1, 0, 1}; /* one byte short */
    wire_feed(cut, sizeof cut);
    wire_run_ms(H4_PACKET_TIMEOUT_MS + 2);
    CHECK(robot_state.errors.bt_wire == 1 && robot_state.errors.bt_resets == 1, "wire %u resets %u",
          robot_state.errors.bt_wire, robot_state.errors.bt_resets);
}

static void a_full_receive_ring_is_a_wire_error(void)
{
    wire_bring_up(27, 64);
    uint8_t flood[300];
    memset(flood, 0, sizeof flood);
    wire_feed(flood, sizeof flood); /* more than the ring holds before the stack reads */
    wire_run_ms(1);
    CHECK(robot_state.errors.bt_wire == 1 && robot_state.errors.rx_overflow > 0, "wire %u overflow %u",
          robot_state.errors.bt_wire, robot_state.errors.rx_overflow);
}

static void a_hardware_error_resets(void)
{
    wire_bring_up(27, 64);
    uint8_t code = 1;
    wire_event(0x10, &code, 1);
    wire_run_ms(4);
    CHECK(robot_state.errors.bt_resets == 1 && wire_find_command(0x0C03, 0), "no reset");
}

static void the_controller_buffers_bound_what_is_sent(void)
{
    wire_bring_up(27, 3); /* three ACL buffers: data leaves one for answers */
    wire_connect(phone, 1);
    CHECK(hci_acl_can_send(27, true) && hci_acl_can_send(54, true), "two fragments refused");
    CHECK(!hci_acl_can_send(81, true) && hci_acl_can_send(81, false), "the reserve not kept");
    hci_acl_begin(0, 54);
    uint8_t d[54] = {0};
    hci_acl_put(d, 54);
    hci_acl_end();
    CHECK(!hci_acl_can_send(10, true) && hci_acl_can_send(10, false), "buffers not counted");
    uint8_t done[5] = {1, 1, 0, 2, 0}; /* Number_Of_Completed_Packets: handle 1, 2 packets */
    wire_event(0x13, done, 5);
    wire_run_ms(1);
    CHECK(hci_acl_can_send(54, true), "buffers not given back");
    wire_collect();
    int frags = 0;
    for (int i = 0; i < wire_out_count; i++)
        if (wire_out[i].type == H4_ACL)
            frags++;
    CHECK(frags == 2 && wire_out[wire_out_count - 1].len == 27, "fragments %d", frags);
}

static void a_disconnection_frees_the_buffers_in_flight(void)
{
    wire_bring_up(27, 2);
    wire_connect(phone, 1);
    hci_acl_begin(0, 40);
    uint8_t d[40] = {0};
    hci_acl_put(d, 40);
    hci_acl_end();
    CHECK(!hci_acl_can_send(10, false), "buffers not taken");
    uint8_t gone[4] = {0, 1, 0, 0x08};
    wire_event(0x05, gone, 4);
    wire_connect(laptop, 2);
    CHECK(hci_acl_can_send(54, false), "the lost link's buffers not freed");
}

static void the_local_name_follows_the_robot_id(void)
{
    wire_bring_up(27, 64);
    settings.identity.robot_id = 42;
    wire_run_ms(1);
    const wire_packet_t *c = wire_find_command(0x0C13, 0);
    CHECK(c && memcmp(c->data, "PocketBot-42\0", 13) == 0, "name %.20s", c ? (char *)c->data : "");
}

static void data_for_an_unknown_handle_is_dropped(void)
{
    wire_bring_up(27, 64);
    const uint8_t pdu[] = {2, 0, 0x40, 0, 1, 2};
    wire_acl(9, 2, pdu, sizeof pdu);
    wire_run_ms(1);
    CHECK(robot_state.errors.bt_dropped == 1 && robot_state.errors.bt_resets == 0, "dropped %u",
          robot_state.errors.bt_dropped);
}

void suite_bt_hci(void)
{
    RUN(initialises_the_controller_in_order);
    RUN(accepts_two_links_and_refuses_a_third);
    RUN(pairs_just_works_and_remembers_the_key_in_eeprom);
    RUN(the_oldest_key_gives_way);
    RUN(a_command_unanswered_resets_the_controller_and_drops_the_links);
    RUN(no_command_credit_for_long_resets_the_controller);
    RUN(a_controller_power_cycled_unnoticed_is_found_by_the_keep_alive);
    RUN(a_garbage_burst_is_counted_and_survived);
    RUN(a_lost_byte_stalls_a_packet_and_resets);
    RUN(a_full_receive_ring_is_a_wire_error);
    RUN(a_hardware_error_resets);
    RUN(the_controller_buffers_bound_what_is_sent);
    RUN(a_disconnection_frees_the_buffers_in_flight);
    RUN(the_local_name_follows_the_robot_id);
    RUN(data_for_an_unknown_handle_is_dropped);
}
