package org.pocketbot.sdk.transport

import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.time.Duration.Companion.milliseconds

/** Link rates as docs/protocol.md gives them: 115200 Bd carries 11520 bytes a second, a full state in 8.6 ms. */
class LinkRateTest {
    @Test
    fun aFrameTakesItsWireBytesAtTheLinksRate() {
        val serial = LinkRate.SERIAL_115200
        assertEquals(11_520, serial.bytesPerSecond)
        // state_full: 92 bytes of payload, 99 on the wire; state_reduced: 19, 26 on the wire.
        assertEquals(8593, serial.frameTime(92).inWholeMicroseconds)
        assertEquals(2256, serial.frameTime(19).inWholeMicroseconds)
    }

    @Test
    fun aPeriodLeavesTheRestOfTheLinkFree() {
        val serial = LinkRate.SERIAL_115200
        assertEquals(4.milliseconds, serial.periodFor(19, share = 0.6))
        assertEquals(3.milliseconds, serial.periodFor(19, share = 1.0))
        assertEquals(9.milliseconds, serial.periodFor(92, share = 1.0))
        assertEquals(1.milliseconds, LinkRate(1_000_000).periodFor(19, share = 0.5))
        assertFailsWith<IllegalArgumentException> { serial.periodFor(19, share = 0.0) }
        assertFailsWith<IllegalArgumentException> { LinkRate(0) }
    }
}
