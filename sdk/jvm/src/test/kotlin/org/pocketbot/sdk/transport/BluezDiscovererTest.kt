package org.pocketbot.sdk.transport

import java.io.File
import java.io.FileInputStream
import java.io.FileOutputStream
import java.nio.file.Files
import kotlin.test.AfterTest
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.async
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.onStart
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.Assumptions.assumeTrue
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo

/** [BluezDiscoverer] against python-dbusmock's BlueZ 5 template on a private D-Bus daemon. */
class BluezDiscovererTest {
    private val toClose = mutableListOf<AutoCloseable>()

    @AfterTest
    fun cleanUp() = toClose.reversed().forEach { runCatching { it.close() } }

    private fun test(block: suspend CoroutineScope.() -> Unit): Unit =
        runBlocking(Dispatchers.IO) { withTimeout(60.seconds) { block() } }

    private fun bluez(withBluez: Boolean = true): BluezMock {
        assumeTrue(BluezMock.available, "dbus-daemon or python3-dbusmock is not installed")
        return BluezMock(withBluez).also { toClose += it }
    }

    @Test
    fun robotsBluezAlreadyKnowsAreReportedByNameOrSerialPortProfile() = test {
        val bluez = bluez()
        bluez.addAdapter("hci0")
        bluez.addDevice("hci0", "00:11:22:33:44:01", "PocketBot-1")
        bluez.addDevice("hci0", "00:11:22:33:44:02", "HC-05", uuids = listOf(BluezDiscoverer.SPP_UUID))
        bluez.addDevice("hci0", "00:11:22:33:44:03", "Somebodys phone", uuids = listOf("0000110a-0000-1000-8000-00805f9b34fb"))
        val found = BluezDiscoverer(duration = 500.milliseconds, busAddress = bluez.address).discover().toList()
        assertEquals(
            setOf("PocketBot-1" to "bluetooth:00:11:22:33:44:01", "HC-05" to "bluetooth:00:11:22:33:44:02"),
            found.map { it.name to it.address }.toSet(),
        )
        assertFalse(bluez.isDiscovering("hci0"), "discovery must be stopped when the search is over")
    }

    @Test
    fun robotsFoundWhileSearchingAreReportedAndDiscoveryRunsMeanwhile() = test {
        val bluez = bluez()
        bluez.addAdapter("hci0")
        val discoverer = BluezDiscoverer(duration = 20.seconds, busAddress = bluez.address)
        val started = kotlinx.coroutines.CompletableDeferred<Unit>()
        val found = async {
            discoverer.discover().onStart { started.complete(Unit) }.first { it.name == "PocketBot-7" }
        }
        started.await()
        // wait for StartDiscovery, as a real adapter would start finding devices only then
        withTimeout(10.seconds) { while (!bluez.isDiscovering("hci0")) delay(20) }
        bluez.addDevice("hci0", "00:11:22:33:44:07", "PocketBot-7")
        val device = found.await() as BluetoothRobotDevice
        assertEquals("00:11:22:33:44:07", device.bluetoothAddress)
        withTimeout(10.seconds) { while (bluez.isDiscovering("hci0")) delay(20) }
    }

    @Test
    fun aRobotWhoseNameArrivesLateIsReportedThen() = test {
        val bluez = bluez()
        bluez.addAdapter("hci0")
        bluez.addDevice("hci0", "00:11:22:33:44:09", "00-11-22-33-44-09")
        val found = async {
            BluezDiscoverer(duration = 20.seconds, busAddress = bluez.address).discover().first()
        }
        withTimeout(10.seconds) { while (!bluez.isDiscovering("hci0")) delay(20) }
        delay(200)
        assertFalse(found.isCompleted, "a device without a robot's name or services is no robot")
        bluez.updateDevice("hci0", "00:11:22:33:44:09", "'Name': 'PocketBot-9', 'Alias': 'PocketBot-9'")
        assertEquals("PocketBot-9", found.await().name)
    }

    @Test
    fun devicesOfAnotherAdapterAreIgnored() = test {
        val bluez = bluez()
        bluez.addAdapter("hci0")
        bluez.addAdapter("hci1")
        bluez.addDevice("hci0", "00:11:22:33:44:01", "PocketBot-1")
        bluez.addDevice("hci1", "00:11:22:33:44:02", "PocketBot-2")
        val found = BluezDiscoverer("hci1", duration = 300.milliseconds, busAddress = bluez.address).discover().toList()
        assertEquals(listOf("PocketBot-2"), found.map { it.name })
    }

    @Test
    fun aFoundRobotOpensThroughItsRfcommTty() = test {
        val bluez = bluez()
        assumeTrue(Socat.available, "socat is not installed")
        bluez.addAdapter("hci0")
        bluez.addDevice("hci0", "00:11:22:33:44:05", "PocketBot-5")
        // a pty pair stands in for /dev/rfcomm0 and the robot behind it
        val socat = Socat.ptyPair().also { toClose += it }
        val (tty, robotSide) = socat.links
        val robot = FakeRobot(FileInputStream(robotSide), FileOutputStream(robotSide), FakeRobot.hello(5, "PocketBot-5"))
        toClose += robot
        val device = BluezDiscoverer(duration = 300.milliseconds, busAddress = bluez.address,
            ttyFor = mapOf("00:11:22:33:44:05" to tty.path)::get).discover().first()
        val t = device.open()
        assertEquals("serial:${tty.path}", t.address)
        t.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 1L), seq = 3))
        assertEquals(FrameResult.Decoded(3, robot.hello), Frames.decode(t.incoming.receive()))
        t.close()
    }

    @Test
    fun aRobotWithoutABoundTtySaysHowToBindOne() = test {
        val bluez = bluez()
        bluez.addAdapter("hci0")
        bluez.addDevice("hci0", "00:11:22:33:44:06", "PocketBot-6")
        val device = BluezDiscoverer(duration = 300.milliseconds, busAddress = bluez.address, ttyFor = { null })
            .discover().first()
        val e = assertFailsWith<TransportLostException> { device.open() }
        assertTrue(e.message!!.contains("rfcomm bind 0 00:11:22:33:44:06 1"), e.message)
    }

    @Test
    fun aMissingAdapterFailsWithTransportLost() = test {
        val bluez = bluez()
        val e = assertFailsWith<TransportLostException> {
            BluezDiscoverer("hci3", duration = 300.milliseconds, busAddress = bluez.address).discover().toList()
        }
        assertTrue(e.message!!.startsWith("bluetooth hci3: cannot start discovery"), e.message)
    }

    @Test
    fun noBluezOnTheBusFailsWithTransportLost() = test {
        val bus = bluez(withBluez = false)
        val e = assertFailsWith<TransportLostException> {
            BluezDiscoverer(duration = 300.milliseconds, busAddress = bus.address).discover().toList()
        }
        assertTrue(e.message!!.startsWith("bluetooth hci0: cannot"), e.message)
    }

    @Test
    fun rfcommTtysAreReadFromSysfs() {
        val sys = Files.createTempDirectory("sysclasstty").toFile()
        try {
            fun tty(name: String, address: String?) = File(sys, name).apply {
                mkdirs(); if (address != null) File(this, "address").writeText("$address\n")
            }
            tty("rfcomm0", "00:11:22:33:44:0a")
            tty("rfcomm1", "00:00:00:00:00:00")
            tty("rfcomm2", null)
            tty("ttyS0", "not rfcomm")
            assertEquals(mapOf("00:11:22:33:44:0A" to "/dev/rfcomm0"), RfcommTtys.bound(sys))
            assertEquals(emptyMap(), RfcommTtys.bound(File(sys, "missing")))
        } finally {
            sys.deleteRecursively()
        }
    }
}
