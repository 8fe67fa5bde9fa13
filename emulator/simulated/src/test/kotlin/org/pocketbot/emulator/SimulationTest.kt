package org.pocketbot.emulator

import kotlinx.coroutines.awaitCancellation
import kotlinx.coroutines.delay
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/** runSimulated's promises: the program's clock is the emulator's, and a program that waits forever is stopped. */
class SimulationTest {
    @Test
    fun `a delay lasts exactly as many emulator steps as its milliseconds`() = Emulator.local(robots = 1).use { emu ->
        val before = emu.time
        val seen = emu.runSimulated {
            delay(2.seconds)
            emu.time
        }
        assertEquals(2.seconds, seen - before, "simulated time that passed during delay(2 s)")
    }

    @Test
    fun `a program that waits for ever is abandoned at the limit, in simulated time`() = Emulator.local(robots = 1).use { emu ->
        val e = assertFailsWith<IllegalStateException> { emu.runSimulated(limit = 500.milliseconds) { awaitCancellation() } }
        assertTrue("within 500ms" in e.message!!, "message: ${e.message}")
        assertTrue(emu.time in 500.milliseconds..510.milliseconds, "the emulator ran ${emu.time}")
    }

    @Test
    fun `an emulator running on its own thread is no simulated run`() = Emulator.local(robots = 1).use { emu ->
        emu.start(Speed.Realtime(1.0))
        val e = assertFailsWith<IllegalStateException> { emu.runSimulated { } }
        assertTrue("stop() it" in e.message!!, "message: ${e.message}")
    }
}
