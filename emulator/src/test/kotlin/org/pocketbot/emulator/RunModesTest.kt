package org.pocketbot.emulator

import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/** Running on the emulator's own thread (speed, pause, single step) and finding robots in process. */
class RunModesTest {
    @Test
    fun `real time runs at about wall-clock speed, pause stops time and single step advances 1 ms`() = RealFirmware.emulator("round").use { emu ->
        emu.addRobot()
        val wall0 = System.nanoTime()
        emu.start(Speed.Realtime(1.0))
        Thread.sleep(500)
        emu.pause()
        val wallMs = (System.nanoTime() - wall0) / 1_000_000
        Thread.sleep(50)
        val t = emu.timeTicks
        val simMs = SimTime.toDuration(t).inWholeMilliseconds
        assertTrue(simMs in (wallMs / 2)..(wallMs + 50), "after $wallMs ms of real time the emulator is at $simMs ms")
        Thread.sleep(100)
        assertEquals(t, emu.timeTicks, "time moved while paused")
        emu.singleStep()
        assertEquals(t + SimTime.STEP_TICKS, emu.timeTicks)
        emu.speed = Speed.AsFastAsPossible
        emu.resume()
        Thread.sleep(500)
        emu.stop()
        assertTrue(emu.time.inWholeMilliseconds > simMs + 1500, "as fast as possible reached only ${emu.time} in 0.5 s")
    }

    @Test
    fun `the discoverer finds every robot and connects to it`() = RealFirmware.emulator("round").use { emu ->
        repeat(3) { emu.addRobot() }
        emu.start(Speed.Realtime(4.0))
        runBlocking {
            val devices = emu.discoverer().discover().toList()
            assertEquals(listOf("PocketBot-1", "PocketBot-2", "PocketBot-3"), devices.map { it.name })
            assertEquals("emulator:3", devices[2].address)
            val t = devices[2].open()
            t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION), 0))
            val hello = withTimeout(5000) {
                var h: Hello? = null
                while (h == null) {
                    val r = Frames.decode(t.incoming.receive())
                    if (r is FrameResult.Decoded && r.packet is Hello) h = r.packet as Hello
                }
                h
            }
            assertEquals(3, hello.robotId)
            t.close()
        }
        emu.stop()
    }
}
