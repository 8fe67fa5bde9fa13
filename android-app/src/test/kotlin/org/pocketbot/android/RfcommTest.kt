package org.pocketbot.android

import android.Manifest
import android.bluetooth.BluetoothAdapter
import android.bluetooth.BluetoothDevice
import android.bluetooth.BluetoothSocket
import android.content.Intent
import android.os.Looper
import android.view.MotionEvent
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.CoroutineStart
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.async
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeoutOrNull
import org.junit.After
import org.junit.Test
import org.junit.runner.RunWith
import org.pocketbot.android.bluetooth.AndroidBluetoothDiscoverer
import org.pocketbot.android.bluetooth.AndroidBluetoothTransport
import org.pocketbot.android.bluetooth.BluetoothRobotDevice
import org.pocketbot.android.model.RobotSession
import org.pocketbot.android.ui.JoystickCanvas
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.Speed
import org.pocketbot.protocol.LocoMode
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import org.robolectric.RuntimeEnvironment
import org.robolectric.Shadows.shadowOf
import org.robolectric.annotation.Config
import org.robolectric.annotation.Implementation
import org.robolectric.annotation.Implements
import org.robolectric.annotation.RealObject
import org.robolectric.shadow.api.Shadow
import org.robolectric.shadows.ShadowBluetoothSocket
import java.io.IOException
import java.io.InputStream
import java.net.Socket
import java.util.UUID
import java.util.concurrent.ConcurrentHashMap
import java.util.concurrent.CopyOnWriteArrayList
import kotlin.concurrent.thread
import kotlin.math.abs
import kotlin.math.cos
import kotlin.math.sin
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * Robolectric's Bluetooth socket for every RFCOMM connect, its streams bridged to an emulated robot's serial link
 * (the emulator's TCP endpoint carries the same bytes a robot's Bluetooth module does): [AndroidBluetoothTransport]
 * and the SDK's SLIP framing run on these bytes exactly as on a phone. A robot can go out of range and come back, and
 * Bluetooth can be switched off: the links break as Android breaks them.
 */
@Implements(BluetoothDevice::class)
class BridgedBluetoothDevice {
    @RealObject
    private lateinit var device: BluetoothDevice

    @Implementation
    protected fun getName(): String? = names[device.address]

    @Implementation
    protected fun createRfcommSocketToServiceRecord(uuid: UUID): BluetoothSocket = socket(uuid, secure = true)

    @Implementation
    protected fun createInsecureRfcommSocketToServiceRecord(uuid: UUID): BluetoothSocket = socket(uuid, secure = false)

    private fun socket(uuid: UUID, secure: Boolean): BluetoothSocket {
        // As Android does: no RFCOMM socket while the adapter is off (an IOException without a message).
        if (!BluetoothAdapter.getDefaultAdapter().isEnabled) throw IOException()
        val socket = Shadow.newInstanceOf(BluetoothSocket::class.java)
        val shadow = Shadow.extract<AndroidBluetoothSocket>(socket)
        sockets += socket
        lastUuid = uuid
        if (device.address in outOfRange || (secure && device.address in refusingSecure)) {
            // Android's words when nothing answers an RFCOMM connect.
            shadow.refuse = IOException("read failed, socket might closed or timeout, read ret: -1")
        } else {
            val port = robots[device.address] ?: throw IOException("no robot at ${device.address}")
            bridges += Bridge(device.address, socket, shadow, port)
        }
        return socket
    }

    /** One RFCOMM link: the socket's streams pumped to and from the robot's TCP endpoint. */
    class Bridge(val address: String, private val real: BluetoothSocket, socket: ShadowBluetoothSocket, port: Int) {
        private val tcp = Socket("127.0.0.1", port)
        private val toPhone = socket.inputStreamFeeder
        private val fromPhone = socket.outputStreamSink
        @Volatile private var cut = false

        init {
            thread(isDaemon = true, name = "rfcomm robot->phone") {
                try {
                    val bytes = tcp.getInputStream()
                    val buffer = ByteArray(256)
                    while (!cut) {
                        val n = bytes.read(buffer)
                        if (n < 0) break
                        toPhone.write(buffer, 0, n)
                        toPhone.flush()
                    }
                } catch (e: IOException) {
                    // the link went down
                } finally {
                    toPhone.close()
                }
            }
            // Polls: the shadow socket's close() does not wake a read of its pipe, as a real socket's does.
            thread(isDaemon = true, name = "rfcomm phone->robot") {
                val buffer = ByteArray(256)
                var connected = false
                try {
                    while (!cut) {
                        if (real.isConnected) connected = true else if (connected) break // the phone closed it
                        if (fromPhone.available() == 0) {
                            Thread.sleep(1)
                            continue
                        }
                        val n = fromPhone.read(buffer)
                        if (n < 0) break
                        tcp.getOutputStream().write(buffer, 0, n)
                    }
                } catch (e: IOException) {
                    // the robot's side went away
                } finally {
                    tcp.close()
                    toPhone.close()
                }
            }
        }

        /** The radio link breaks: the robot hears nothing more, the phone's next read fails. */
        fun cut() {
            cut = true
            tcp.close()
            toPhone.close()
        }
    }

    companion object {
        /** Bluetooth address -> the device's name. */
        val names = HashMap<String, String>()

        /** Bluetooth address -> the emulated robot's TCP port. */
        val robots = HashMap<String, Int>()
        val sockets: MutableList<BluetoothSocket> = CopyOnWriteArrayList()
        val bridges: MutableList<Bridge> = CopyOnWriteArrayList()
        private val outOfRange: MutableSet<String> = ConcurrentHashMap.newKeySet()

        /** Robots whose module refuses a secure (authenticated, encrypted) RFCOMM link, as some serial modules do. */
        val refusingSecure: MutableSet<String> = ConcurrentHashMap.newKeySet()
        @Volatile var lastUuid: UUID? = null

        /** The robot at [address] leaves the phone's range: its links break, and connecting fails until [backInRange]. */
        fun goOutOfRange(address: String) {
            outOfRange += address
            bridges.filter { it.address == address }.forEach { it.cut() }
        }

        fun backInRange(address: String) {
            outOfRange -= address
        }

        /** Bluetooth is switched off: Android closes every RFCOMM socket. */
        fun cutEveryLink() = bridges.forEach { it.cut() }

        fun reset() {
            bridges.forEach { it.cut() }
            bridges.clear()
            robots.clear()
            sockets.clear()
            names.clear()
            outOfRange.clear()
            refusingSecure.clear()
        }
    }
}

/**
 * Android's RFCOMM socket as far as the app can tell: a read on a link that broke throws (Android's
 * BluetoothInputStream says "bt socket closed, read return: -1"), it never returns end of stream; and a connect to a
 * device that does not answer fails ([refuse]).
 */
@Implements(BluetoothSocket::class)
class AndroidBluetoothSocket : ShadowBluetoothSocket() {
    /** What [connect] throws, or null when the device answers. */
    @Volatile var refuse: IOException? = null

    @Implementation
    override fun connect() {
        refuse?.let { throw it }
        super.connect()
    }

    private val input: InputStream by lazy {
        val pipe = super.getInputStream()
        object : InputStream() {
            override fun read(): Int = ByteArray(1).let { if (read(it, 0, 1) < 0) -1 else it[0].toInt() and 0xFF }
            override fun read(b: ByteArray, off: Int, len: Int): Int {
                val n = pipe.read(b, off, len)
                if (n < 0) throw IOException("bt socket closed, read return: -1")
                return n
            }
            override fun available(): Int = pipe.available()
            override fun close() = pipe.close()
        }
    }

    @Implementation
    override fun getInputStream(): InputStream = input
}

@RunWith(org.robolectric.RobolectricTestRunner::class)
@Config(sdk = [35], application = TestApp::class, qualifiers = "w360dp-h760dp-xhdpi",
    shadows = [BridgedBluetoothDevice::class, AndroidBluetoothSocket::class])
class RfcommTest {
    private val emulator = Emulator.local(robots = 1, world = "round")
    private val robot: RobotHandle = emulator.robots.single()
    private val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)

    @After
    fun close() {
        scope.coroutineContext[kotlinx.coroutines.Job]?.cancel()
        emulator.close()
        BridgedBluetoothDevice.reset()
    }

    @Test
    fun aPairedRobotIsFoundConnectedOverRfcommAndDriven() = runBlocking {
        val app = RuntimeEnvironment.getApplication()
        shadowOf(app).grantPermissions(Manifest.permission.BLUETOOTH_SCAN, Manifest.permission.BLUETOOTH_CONNECT)
        val adapter = BluetoothAdapter.getDefaultAdapter()
        shadowOf(adapter).setEnabled(true)
        val pocketBot = adapter.getRemoteDevice("00:11:22:33:44:55")
        val headphones = adapter.getRemoteDevice("66:77:88:99:AA:BB")
        BridgedBluetoothDevice.names[pocketBot.address] = "PocketBot-1"
        BridgedBluetoothDevice.names[headphones.address] = "Headphones"
        shadowOf(adapter).setBondedDevices(setOf(pocketBot, headphones))
        val nearby = adapter.getRemoteDevice("00:11:22:33:44:66")
        emulator.start(Speed.Realtime(1.0))
        BridgedBluetoothDevice.robots[pocketBot.address] = robot.startTcp()

        // Discovery: the paired PocketBot, then one found nearby, and one whose name Android resolves only later
        // (found nameless, then ACTION_NAME_CHANGED); the headphones are no robot.
        val unnamed = adapter.getRemoteDevice("00:11:22:33:44:77")
        suspend fun discover(everyDevice: Boolean): List<org.pocketbot.sdk.transport.RobotDevice> {
            val search = async { AndroidBluetoothDiscoverer(app, adapter, everyDevice).discover().toList() }
            withTimeoutOrNull(5.seconds) { while (!adapter.isDiscovering) delay(10) } ?: throw AssertionError("no discovery started")
            app.sendBroadcast(Intent(BluetoothDevice.ACTION_FOUND).putExtra(BluetoothDevice.EXTRA_DEVICE, nearby).putExtra(BluetoothDevice.EXTRA_NAME, "PocketBot-7"))
            app.sendBroadcast(Intent(BluetoothDevice.ACTION_FOUND).putExtra(BluetoothDevice.EXTRA_DEVICE, unnamed))
            shadowOf(Looper.getMainLooper()).idle()
            app.sendBroadcast(Intent(BluetoothDevice.ACTION_NAME_CHANGED).putExtra(BluetoothDevice.EXTRA_DEVICE, unnamed).putExtra(BluetoothDevice.EXTRA_NAME, "PocketBot-9"))
            app.sendBroadcast(Intent(BluetoothAdapter.ACTION_DISCOVERY_FINISHED))
            shadowOf(Looper.getMainLooper()).idle()
            return withTimeoutOrNull(5.seconds) { search.await() } ?: throw AssertionError("the discovery did not end")
        }
        assertEquals(listOf("PocketBot-7", "00:11:22:33:44:77", "PocketBot-9").let { listOf("PocketBot-1", "Headphones") + it },
            discover(everyDevice = true).map { it.name }, "every device, the nameless one by its address, then again by its name")
        adapter.cancelDiscovery()
        val found = discover(everyDevice = false)
        assertEquals(listOf("PocketBot-1", "PocketBot-7", "PocketBot-9"), found.map { it.name })
        val device = found.first() as BluetoothRobotDevice
        assertEquals("bluetooth:00:11:22:33:44:55", device.address)

        // Connected over the shadow RFCOMM socket: handshake, settings, state, all SLIP on the socket's streams.
        val connected = device.connect(scope, RobotOptions { settingsCache = InMemorySettingsCache() })
        assertEquals(AndroidBluetoothTransport.SPP_UUID, BridgedBluetoothDevice.lastUuid)
        assertEquals(robot.name, connected.identity.name)
        withTimeoutOrNull(5.seconds) { connected.power.reading.first { it.batteryMv > 3000 } }
            ?: throw AssertionError("no state over RFCOMM: ${connected.linkStats.value}, ${connected.connection.value}")

        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0))
        val start = robot.truePose
        repeat(10) {
            connected.locomotion.setWheelSpeeds(0.1, 0.1)
            delay(100)
        }
        connected.locomotion.stop()
        val end = robot.truePose
        val along = (end.xM - start.xM) * cos(start.headingRad) + (end.yM - start.yM) * sin(start.headingRad)
        assertTrue(along > 0.04, "driven over Bluetooth: ${along * 1000} mm forward")
        assertTrue(connected.linkStats.value.dropped == 0L, "no frame lost on the way: ${connected.linkStats.value}")

        connected.disconnect()
        assertTrue(BridgedBluetoothDevice.sockets.none { it.isConnected }, "disconnecting closed the RFCOMM socket")
        assertEquals(ConnectionState.Closed(null), connected.connection.value)
    }

    @Test
    fun aRobotThatGoesOutOfRangeMidDriveStopsOnItsOwnAndTheAppReconnectsWhenItIsBack() = withBluetoothApp {
        val session = driveOverBluetooth()
        val robot = emulator.robots.single()
        val steps = record(session)

        BridgedBluetoothDevice.goOutOfRange(PAIRED)
        val lostAt = emulator.time
        until("the app notices the loss") { session.robot.connection.value != ConnectionState.Connected }
        assertStopsByItsFailsafe(robot, lostAt)
        assertTrue(shows("Link to PocketBot-1 lost") && shows("bt socket closed"), "the user reads that the link broke: ${texts()}")
        assertTrue(shows("Stopped: the link was lost"), "and why the robot stopped: ${texts()}")

        // Out of range, every reconnect fails as Android's RFCOMM connect does; the app keeps trying.
        until("three reconnect attempts fail") { failedAttempts(steps).size >= 3 }
        assertTrue(failedAttempts(steps).all { "read failed, socket might closed or timeout" in it }, "${failedAttempts(steps)}")
        assertTrue(shows("link lost") || shows("reconnecting"), "the status bar says the link is down: ${texts()}")

        BridgedBluetoothDevice.backInRange(PAIRED)
        until("the SDK reconnects over a new RFCOMM socket") { session.robot.connection.value == ConnectionState.Connected }
        assertTrue(session.robot.linkStats.value.reconnects >= 1, "${session.robot.linkStats.value}")
        until("the user reads that it is back") { shows("Link to PocketBot-1 is back") }
        assertStaysStill(robot, "the robot does not drive off again when the link returns")
        assertEquals(session, model.session.value, "the same session goes on")
    }

    @Test
    fun switchingBluetoothOffMidDriveIsExplainedTheRobotStopsAndTurningItOnReconnects() = withBluetoothApp {
        val session = driveOverBluetooth()
        val robot = emulator.robots.single()
        val adapter = BluetoothAdapter.getDefaultAdapter()
        val steps = record(session)

        // The user switches Bluetooth off: Android closes every RFCOMM socket and tells the apps.
        shadowOf(adapter).setEnabled(false)
        BridgedBluetoothDevice.cutEveryLink()
        val lostAt = emulator.time
        app.sendBroadcast(Intent(BluetoothAdapter.ACTION_STATE_CHANGED).putExtra(BluetoothAdapter.EXTRA_STATE, BluetoothAdapter.STATE_OFF))
        until("the app notices the loss") { session.robot.connection.value != ConnectionState.Connected }
        assertStopsByItsFailsafe(robot, lostAt)
        assertTrue(shows("Bluetooth is off, so the link to PocketBot-1 is lost") && shows("Turn Bluetooth on and the app reconnects"),
            "the user reads why and what to do: ${texts()}")
        until("three reconnect attempts fail while Bluetooth is off") { failedAttempts(steps).size >= 3 }
        assertTrue(failedAttempts(steps).all { "Bluetooth is off" in it }, "${failedAttempts(steps)}")

        shadowOf(adapter).setEnabled(true)
        app.sendBroadcast(Intent(BluetoothAdapter.ACTION_STATE_CHANGED).putExtra(BluetoothAdapter.EXTRA_STATE, BluetoothAdapter.STATE_ON))
        until("the SDK reconnects once Bluetooth is on") { session.robot.connection.value == ConnectionState.Connected }
        until("the user reads that it is back") { shows("Link to PocketBot-1 is back") }
        assertStaysStill(robot, "the robot does not drive off again when the link returns")
    }

    /**
     * A robot that discovery does not name (a module never renamed), typed in by its address, whose module refuses a
     * secure RFCOMM link: the app falls back to an insecure one, says so, and drives the robot.
     */
    @Test
    fun aRobotTypedInByAddressThatRefusesSecureRfcommIsConnectedInsecurelyAndSaysSo() = withBluetoothApp {
        BridgedBluetoothDevice.names.remove(PAIRED)
        BridgedBluetoothDevice.refusingSecure += PAIRED
        shadowOf(BluetoothAdapter.getDefaultAdapter()).setBondedDevices(emptySet())
        launch()
        field("Bluetooth address").setText(PAIRED.lowercase())
        click("Connect to address")
        until("connected over RFCOMM") { model.session.value != null }
        assertEquals("bluetooth:$PAIRED", model.session.value!!.address)
        until("the user reads which link is used") { shows("insecure RFCOMM (not encrypted") }
        click("Robots")
        assertTrue(shows("insecure RFCOMM"), "the connected robot's card names the link: ${texts()}")
        val robot = emulator.robots.single()
        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0))
        click("Drive")
        val stick = find<JoystickCanvas>()
        val start = robot.trueWheelDistances
        push(stick, 0.5f, 0.3f)
        until("the robot drives") { robot.trueWheelDistances.leftM - start.leftM > 0.02 }
        touch(stick, MotionEvent.ACTION_UP, 0.5f, 0.3f)
    }

    /** Every step of the session's connection from now on, as the SDK reports them. */
    private fun record(session: RobotSession): List<ConnectionState> {
        val steps = CopyOnWriteArrayList<ConnectionState>()
        scope.launch(start = CoroutineStart.UNDISPATCHED) { session.robot.connectionChanges.collect { steps += it.state } }
        return steps
    }

    /** Why each failed reconnect attempt failed. */
    private fun failedAttempts(steps: List<ConnectionState>): List<String> =
        steps.filterIsInstance<ConnectionState.Lost>().map { it.reason }.filter { it.startsWith("reconnect attempt") }

    /** Finds the paired robot, connects it through the robot list and drives it forward with the joystick. */
    private suspend fun AppHarness.driveOverBluetooth(): RobotSession {
        launch()
        click("Find robots")
        until("the paired robot is listed") { model.found.value.any { it.name == "PocketBot-1" } }
        click("Connect")
        until("connected over RFCOMM") { model.session.value != null }
        val session = model.session.value!!
        assertEquals("bluetooth:$PAIRED", session.address)
        val robot = emulator.robots.single()
        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0)) // open floor inside the track
        click("Drive")
        val stick = find<JoystickCanvas>()
        push(stick, 0.5f, 0.3f)
        val start = robot.trueWheelDistances
        until("the robot drives") { robot.trueWheelDistances.leftM - start.leftM > 0.02 }
        assertEquals(LocoMode.TELEOP, robot.state().locomotion.mode, "driven by the joystick")
        return session
    }

    /** The robot, cut off from the phone at simulated [lostAt], stops by its own link failsafe and stands. */
    private suspend fun AppHarness.assertStopsByItsFailsafe(robot: RobotHandle, lostAt: kotlin.time.Duration) {
        until("the robot's failsafe stops it") { robot.state().locomotion.mode == LocoMode.FAILSAFE }
        val after = emulator.time - lostAt
        assertTrue(after <= 1500.milliseconds, "the failsafe (1 s without the host) stopped the robot $after after the link broke")
        assertStaysStill(robot, "the robot stands after its failsafe")
    }

    /** Over one second of simulated time (from 300 ms on, once the wheels spun down) the robot moves less than 1 mm. */
    private suspend fun AppHarness.assertStaysStill(robot: RobotHandle, what: String) {
        val from = emulator.time
        until("300 ms of simulated time") { emulator.time >= from + 300.milliseconds }
        val a = robot.trueWheelDistances
        val t = emulator.time
        until("1 s more of simulated time") { emulator.time >= t + 1.seconds }
        val b = robot.trueWheelDistances
        assertTrue(abs(b.leftM - a.leftM) + abs(b.rightM - a.rightM) < 0.001, "$what: $a -> $b")
    }

    /**
     * Runs [block] with the app on a phone whose Bluetooth has the emulated robot paired at [PAIRED], reached over
     * RFCOMM bridged to its TCP endpoint; the emulator runs on its own in real time, the app on the main thread.
     */
    private fun withBluetoothApp(block: suspend AppHarness.() -> Unit) {
        val adapter = BluetoothAdapter.getDefaultAdapter()
        shadowOf(adapter).setEnabled(true)
        val device = adapter.getRemoteDevice(PAIRED)
        BridgedBluetoothDevice.names[PAIRED] = robot.name
        shadowOf(adapter).setBondedDevices(setOf(device))
        emulator.start(Speed.Realtime(1.0))
        BridgedBluetoothDevice.robots[PAIRED] = robot.startTcp()
        withRealTimeApp(emulator, block)
    }

    private companion object {
        const val PAIRED = "00:11:22:33:44:55"
    }
}
