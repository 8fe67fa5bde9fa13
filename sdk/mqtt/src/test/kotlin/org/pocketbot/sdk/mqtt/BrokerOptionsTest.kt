package org.pocketbot.sdk.mqtt

import org.junit.jupiter.api.Test
import java.io.File
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** Broker URLs and options: what is accepted, and what is refused with a message that says why. */
class BrokerOptionsTest {
    @Test
    fun urlsGiveTheHostAndThePortOrItsDefault() {
        assertEquals("broker.lab:1883", BrokerOptions("mqtt://broker.lab").hostPort)
        assertEquals("broker.lab:8883", BrokerOptions("mqtts://broker.lab").hostPort)
        assertEquals("10.0.0.2:1999", BrokerOptions("MQTT://10.0.0.2:1999").hostPort)
        assertEquals("[::1]:8883", BrokerOptions("mqtts://[::1]").hostPort)
        assertTrue(BrokerOptions("mqtts://h").tls)
        assertFalse(BrokerOptions("mqtt://h/").tls)
    }

    @Test
    fun badUrlsAreRefusedSayingWhy() {
        for ((url, why) in listOf(
            "broker.lab:1883" to "scheme", "http://broker.lab" to "not mqtt or mqtts", "mqtt://" to "not a URL", "mqtt://:1883" to "no host",
            "mqtt://h:70000" to "port", "mqtt://alice:pw@h" to "username", "mqtt://h/pb/v1" to "path",
            "mqtt://h?x=1" to "query", "mqtt://h h" to "not a URL", "" to "scheme",
        )) {
            val e = assertFailsWith<IllegalArgumentException>(url) { BrokerOptions(url) }
            assertTrue(why in e.message!!, "$url: ${e.message}")
        }
    }

    @Test
    fun optionsAreCheckedAndThePasswordNeverShows() {
        val options = BrokerOptions("mqtts://h") { username = "alice"; password = "s3cret".toCharArray(); trustedCertificates = File("ca.crt") }
        assertFalse("s3cret" in options.toString(), options.toString())
        assertEquals(500.milliseconds, options.maxFrameAge)
        assertEquals(10.milliseconds, options.upBatchWindow)
        assertFailsWith<IllegalArgumentException> { BrokerOptions("mqtt://h") { trustedCertificates = File("ca.crt") } }
        assertFailsWith<IllegalArgumentException> { BrokerOptions("mqtt://h") { maxFrameAge = 0.milliseconds } }
        assertFailsWith<IllegalArgumentException> { BrokerOptions("mqtt://h") { clientId = "a/b" } }
    }
}
