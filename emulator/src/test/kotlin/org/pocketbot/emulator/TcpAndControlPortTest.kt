package org.pocketbot.emulator

import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import org.junit.jupiter.api.Assumptions.assumeTrue
import org.pocketbot.emulator.transport.ListenAddress
import java.net.ConnectException
import java.net.Inet4Address
import java.net.InetAddress
import java.net.InetSocketAddress
import java.net.NetworkInterface
import java.net.Socket
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotNull
import kotlin.test.assertNull
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
        assertEquals(listOf("127.0.0.1"), fields.map { it[3] }.distinct(), "each line names the host the client reached")

        val hello = hello(emu, InetSocketAddress(InetAddress.getLoopbackAddress(), port))
        assertEquals(2, hello.robotId)
        assertEquals(ProtocolInfo.LAYOUT_HASH, hello.layoutHash)
    }

    @Test
    fun `by default only this machine reaches the robots`() = RealFirmware.emulator("round").use { emu ->
        val robot = emu.addRobot()
        val control = emu.startTcp(basePort = 0, controlPort = 0)
        val network = networkAddress()
        assumeTrue(network != null, "this machine has no network address besides loopback: nothing to refuse from")
        for (port in listOf(control, robot.tcpPort)) {
            assertFailsWith<ConnectException>("port $port must not answer at $network") { Socket(network, port).close() }
        }
        assertEquals(1, controlLines(InetSocketAddress(InetAddress.getLoopbackAddress(), control)).size)
    }

    @Test
    fun `on the wildcard address the control port names the network address the client reached and the robot answers there`() =
        RealFirmware.emulator("round").use { emu ->
            val robot = emu.addRobot()
            val control = emu.startTcp(basePort = 0, controlPort = 0, listen = ListenAddress.ANY)
            // From this machine itself, loopback still works and is what the line names.
            assertEquals("127.0.0.1", controlLines(InetSocketAddress(InetAddress.getLoopbackAddress(), control)).single()[3])
            val network = networkAddress()
            assumeTrue(network != null, "this machine has no network address besides loopback: the network part cannot run here")
            network!!
            assertTrue(network in ListenAddress.reachable(ListenAddress.ANY), "$network is offered as a reachable address: ${ListenAddress.reachable(ListenAddress.ANY)}")
            val line = controlLines(InetSocketAddress(network, control)).single()
            assertEquals(listOf("1", "PocketBot-1", robot.tcpPort.toString(), network.hostAddress), line)

            assertNull(robot.tcpClient)
            val hello = hello(emu, InetSocketAddress(InetAddress.getByName(line[3]), line[2].toInt())) { client ->
                assertEquals(client, robot.tcpClient, "the robot knows which host holds it")
            }
            assertEquals(1, hello.robotId)
            // The endpoint's reader notices the closed socket on its own thread, in real time.
            val deadline = System.currentTimeMillis() + 5000
            while (robot.tcpClient != null && System.currentTimeMillis() < deadline) Thread.sleep(5)
            assertNull(robot.tcpClient, "the host left")
        }

    @Test
    fun `stopping TCP closes the ports and starting again listens anew`() = RealFirmware.emulator("round").use { emu ->
        val robot = emu.addRobot()
        val control = emu.startTcp(basePort = 0, controlPort = 0)
        val port = robot.tcpPort
        emu.stopTcp()
        assertEquals(-1, robot.tcpPort)
        // Closed: a connection is refused, or, should the system have handed a freed port to another socket in the
        // meantime (or a connect to a free port have met itself), whatever answers there is not this emulator.
        val loopback = InetAddress.getLoopbackAddress()
        val controlAnswer = runCatching {
            Socket().use { it.connect(InetSocketAddress(loopback, control), 1000); it.soTimeout = 1000; it.getInputStream().readBytes() }
        }.getOrNull()?.toString(Charsets.US_ASCII)
        assertTrue(controlAnswer == null || !controlAnswer.startsWith("${robot.id}\t"), "the control port still lists the robot: $controlAnswer")
        assertTrue(runCatching { hello(emu, InetSocketAddress(loopback, port)) }.isFailure, "the robot still answers on port $port")
        val again = emu.startTcp(basePort = 0, controlPort = 0)
        assertEquals(robot.tcpPort.toString(), controlLines(InetSocketAddress(InetAddress.getLoopbackAddress(), again)).single()[2])
    }

    private fun controlLines(at: InetSocketAddress): List<List<String>> =
        Socket().use { it.connect(at, 5000); it.getInputStream().readBytes().toString(Charsets.US_ASCII) }
            .lines().filter { it.isNotEmpty() }.map { it.split('\t') }

    /** Says hello to the robot at [at] over TCP and returns its answer; [connected] runs while the socket is open. */
    private fun hello(emu: Emulator, at: InetSocketAddress, connected: (InetSocketAddress) -> Unit = {}): Hello =
        Socket().use { s ->
            s.connect(at, 5000)
            s.soTimeout = 5000
            s.getOutputStream().write(Slip.encode(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 77L), 0)))
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
            connected(s.localSocketAddress as InetSocketAddress)
            assertNotNull(hello, "no hello over TCP from $at")
        }

    /** An IPv4 address of this machine other than loopback (found here, not by the code under test), or null. */
    private fun networkAddress(): InetAddress? = NetworkInterface.getNetworkInterfaces().toList()
        .filter { it.isUp && !it.isLoopback }
        .flatMap { it.inetAddresses.toList() }
        .firstOrNull { it is Inet4Address && !it.isLoopbackAddress && !it.isLinkLocalAddress }
}
