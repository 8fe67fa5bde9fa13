package org.pocketbot.android

import android.view.MotionEvent
import org.junit.Assume.assumeTrue
import org.junit.Test
import org.junit.runner.RunWith
import org.pocketbot.android.ui.JoystickCanvas
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.sdk.Pose
import org.robolectric.annotation.Config
import java.net.Inet4Address
import java.net.NetworkInterface
import kotlin.math.abs
import kotlin.math.hypot
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/**
 * Someone without a robot: an emulator on a computer of the same network (on every address, as `pocketbot emulator
 * --listen 0.0.0.0` or the panel's "Serve on the network" run it), reached by the app from this machine's network
 * address as a phone on the Wi-Fi reaches it: typed in, found, connected and driven with the joystick.
 */
@RunWith(org.robolectric.RobolectricTestRunner::class)
@Config(sdk = [35], application = TestApp::class, qualifiers = "w360dp-h760dp-xhdpi")
class NetworkEmulatorTest {
    @Test
    fun theAppFindsAnEmulatorOnTheNetworkByItsAddressAndDrivesItsRobot() {
        val network = NetworkInterface.getNetworkInterfaces().toList().filter { it.isUp && !it.isLoopback }
            .flatMap { it.inetAddresses.toList() }.firstOrNull { it is Inet4Address && !it.isLinkLocalAddress }?.hostAddress
        assumeTrue("this machine has no network address besides loopback: a phone's view cannot be tried here", network != null)
        Emulator.local(robots = 2, world = "round").use { emu ->
            val control = emu.startTcp(basePort = 0, controlPort = 0, listen = ListenAddress.ANY)
            emu.start(Speed.Realtime(1.0))
            withRealTimeApp(emu) {
                launch()
                field("Emulator address").setText("$network:$control")
                click("Find")
                until("the emulator's robots are listed") { model.found.value.size == 2 }
                assertEquals(emu.robots.map { "tcp://$network:${it.tcpPort}" }, model.found.value.map { it.address })
                assertTrue(shows("emulator at $network:$control"), "where they were found: ${texts()}")
                click("Connect") // the first: PocketBot-1
                until("connected over the network") { model.session.value != null }
                val robot = emu.robots.first()
                assertEquals("PocketBot-1", model.session.value!!.name)
                assertEquals(network, robot.tcpClient?.address?.hostAddress, "the robot is held from the network address")

                robot.place(Pose.ofDegrees(0.4, 0.4, 90.0)) // open floor inside the track, facing +y
                click("Drive")
                val stick = find<JoystickCanvas>()
                val start = robot.truePose
                push(stick, 0.5f, 0.25f)
                until("the robot drives forward") { robot.truePose.yM - start.yM > 0.05 }
                val end = robot.truePose
                assertTrue(abs(end.xM - start.xM) < 0.01, "straight ahead: $start -> $end")
                touch(stick, MotionEvent.ACTION_UP, 0.5f, 0.25f)
                val released = emu.time
                until("300 ms of simulated time") { emu.time >= released + 300.milliseconds }
                val a = robot.truePose
                val t = emu.time
                until("1 s more of simulated time") { emu.time >= t + 1000.milliseconds }
                assertTrue(hypot(robot.truePose.xM - a.xM, robot.truePose.yM - a.yM) < 0.001, "released, the robot stands")
            }
        }
    }
}
