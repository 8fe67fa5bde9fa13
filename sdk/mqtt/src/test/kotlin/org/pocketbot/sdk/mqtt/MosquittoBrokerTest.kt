package org.pocketbot.sdk.mqtt

import org.junit.jupiter.api.Test
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import kotlin.test.assertFalse
import kotlin.test.assertTrue

/** The test broker starts with the shipped configuration, and stops, restarts, freezes and thaws on demand. */
class MosquittoBrokerTest {
    @Test
    fun startsWithTheShippedConfigurationAndRestartsOnTheSamePorts() {
        MosquittoBroker.start().use { broker ->
            assertTrue(broker.running)
            val tls = broker.tlsPort
            broker.freeze()
            broker.thaw()
            broker.kill()
            assertFalse(broker.running)
            broker.restart()
            assertTrue(broker.running)
            assertTrue(broker.tlsPort == tls)
            assertTrue("mosquitto version" in broker.log.readText(), broker.log.readText())
        }
    }
}
