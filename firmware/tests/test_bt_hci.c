#include <string.h>

#include "bt_wire.h"
#include "bluetooth/hci.h"
#include "core/data.h"
#include "harness.h"

static void comes_up(void)
{
    wire_bring_up(27, 64);
    CHECK(hci_ready(), "not ready");
}

void suite_bt_hci(void)
{
    RUN(comes_up);
}
void suite_bt_h4(void) {}
void suite_bt_l2cap(void) {}
void suite_bt_sdp(void) {}
void suite_bt_rfcomm(void) {}
