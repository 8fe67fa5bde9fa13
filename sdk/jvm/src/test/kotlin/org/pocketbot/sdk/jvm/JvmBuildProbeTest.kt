package org.pocketbot.sdk.jvm

import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith

class JvmBuildProbeTest {
    @Test
    fun formatsEndpoint() {
        assertEquals("tcp://127.0.0.1:7000", JvmBuildProbe.describe("127.0.0.1", 7000))
    }

    @Test
    fun rejectsBadPort() {
        assertFailsWith<IllegalArgumentException> { JvmBuildProbe.describe("localhost", 0) }
    }
}
