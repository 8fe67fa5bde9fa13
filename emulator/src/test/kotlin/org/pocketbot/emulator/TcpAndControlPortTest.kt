package org.pocketbot.emulator

import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import java.net.InetAddress
import java.net.Socket
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** Robots reachable like real ones: TCP endpoints with SLIP frames, and the control port that lists them. */
class TcpAndControlPortTest {
    @Test
    fun `the control port lists every robot and a robot answers hello over TCP`() = RealFirmware.emulator("round").use { emu ->
        repeat(3) { emu.addRobot() }
        val control = emu.startTcp(basePort = 0, controlPort = 0)
        val lines = Socket(InetAddress.getLoopbackAddress(), control).use { it.getInputStream().readBytes().toString(Charsets.US_ASCII) }
            .lines().filter { it.isNotEmpty() }
        assertEquals(3, lines.size, "control port said: $lines")
        val fields = lines.map { it.split('\t') }
        assertEquals(listOf("1", "2", "3"), fields.map { it[0] })
        assertEquals(listOf("PocketBot-1", "PocketBot-2", "PocketBot-3"), fields.map { it[1] })
        val port = fields[1][2].toInt()
        assertEquals(emu.robot(2).tcpPort, port)

        Socket(InetAddress.getLoopbackAddress(), port).use { s ->
            s.soTimeout = 5000
            s.getOutputStream().write(Slip.encode(Frames.encode(HelloRequest(ProtocolInfo.VERSION), 0)))
            s.getOutputStream().flush()
            val decoder = SlipDecoder()
            var hello: Hello? = null
            val buf = ByteArray(1024)
            val deadline = System.currentTimeMillis() + 5000
            while (hello == null && System.currentTimeMillis() < deadline) {
                emu.runFor(20.milliseconds)
                if (s.getInputStream().available() > 0) {
                    val n = s.getInputStream().read(buf)
                    decoder.feed(buf, 0, n) { f -> (Frames.decode(f) as? FrameResult.Decoded)?.let { if (it.packet is Hello) hello = it.packet as Hello } }
                } else Thread.sleep(2)
            }
            assertTrue(hello != null, "no hello over TCP")
            assertEquals(2, hello!!.robotId)
            assertEquals(ProtocolInfo.LAYOUT_HASH, hello!!.layoutHash)
        }
    }
}
