package org.pocketbot.android

import android.Manifest
import android.bluetooth.BluetoothAdapter
import android.graphics.Color
import android.provider.Settings
import android.view.MotionEvent
import android.widget.RadioButton
import org.junit.Test
import org.junit.runner.RunWith
import org.pocketbot.android.model.JoystickModel
import org.pocketbot.android.model.Screen
import org.pocketbot.android.ui.JoystickCanvas
import org.pocketbot.android.ui.palette
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.LineCalibration
import org.pocketbot.sdk.LineFollowStatus
import org.pocketbot.sdk.Pose
import org.robolectric.Shadows.shadowOf
import org.robolectric.annotation.Config
import org.robolectric.annotation.GraphicsMode
import kotlin.math.PI
import kotlin.math.abs
import kotlin.math.atan2
import kotlin.math.cos
import kotlin.math.hypot
import kotlin.math.sin
import kotlin.test.assertEquals
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * The app as a person uses it: real MainActivity and views (Robolectric, native graphics), the robot the real firmware
 * in the emulator, ground truth from the emulator's physics. Every screen is photographed into docs/images/.
 */
@RunWith(org.robolectric.RobolectricTestRunner::class)
@Config(sdk = [35], application = TestApp::class, qualifiers = "w360dp-h760dp-xhdpi")
@GraphicsMode(GraphicsMode.Mode.NATIVE)
class AppTest {
    @Test
    fun joystickDragDrivesTheRobotTheRightWayAndReleaseStopsIt() = withApp(world = "round") {
        connectRobot()
        val robot = emulator.robots.single()
        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0)) // open floor, facing +x
        click("Drive")
        val stick = find<JoystickCanvas>()
        val start = robot.truePose

        push(stick, 0.5f, 0.2f) // knob pushed forward
        run(1.seconds)
        screenshot("drive")
        val forward = robot.truePose
        val along = (forward.xM - start.xM) * cos(start.headingRad) + (forward.yM - start.yM) * sin(start.headingRad)
        assertTrue(along > 0.05, "the robot drove forward ${along * 1000} mm")
        assertTrue(abs(angle(forward.headingRad - start.headingRad)) < 10 * PI / 180, "and kept its heading: $forward")

        touch(stick, MotionEvent.ACTION_MOVE, 0.8f, 0.5f) // knob to the right: turn right in place
        var turned = 0.0
        var heading = robot.truePose.headingRad
        repeat(30) {
            run(10.milliseconds)
            turned += angle(robot.truePose.headingRad - heading)
            heading = robot.truePose.headingRad
        }
        assertTrue(turned < -20 * PI / 180, "the robot turned right (clockwise): ${turned * 180 / PI} deg")

        touch(stick, MotionEvent.ACTION_UP, 0.8f, 0.5f)
        run(400.milliseconds)
        val stopped = robot.trueWheelDistances
        run(1.seconds)
        val after = robot.trueWheelDistances
        assertTrue(abs(after.leftM - stopped.leftM) + abs(after.rightM - stopped.rightM) < 0.002, "released, the robot stands: $stopped -> $after")
        assertTrue(shows("Hold and drag the knob"), "the screen says how to drive again")

        // Leaving the screen while driving stops the robot too.
        touch(stick, MotionEvent.ACTION_DOWN, 0.5f, 0.2f)
        run(300.milliseconds)
        click("Sensor")
        run(400.milliseconds)
        val left = robot.trueWheelDistances
        run(1.seconds)
        assertTrue(abs(robot.trueWheelDistances.leftM - left.leftM) < 0.002, "leaving the joystick screen stopped the robot")
    }

    /**
     * The joystick is safe to touch: a touch beside the pad (the view is wider than the pad) and scrolling the screen do
     * not drive; a thumb resting near the centre does not creep; a touch at the rim speeds up along a ramp.
     */
    @Test
    fun onlyThePadDrivesWithADeadZoneAndARamp() = withApp(world = "round") {
        connectRobot()
        val robot = emulator.robots.single()
        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0))
        click("Drive")
        val stick = find<JoystickCanvas>()
        val scroll = find<android.widget.ScrollView>()
        val joystick = model.session.value!!.joystick
        val start = robot.trueWheelDistances
        fun moved() = abs(robot.trueWheelDistances.leftM - start.leftM) + abs(robot.trueWheelDistances.rightM - start.rightM)

        // Beside the pad: a swipe up that scrolls the screen, and drives nothing.
        swipe(stick, fromX = 0.02f, fromY = 0.9f, toY = 0.1f)
        run(500.milliseconds)
        assertTrue(scroll.scrollY > 0, "the swipe beside the pad scrolled the screen")
        assertEquals(false, joystick.state.value.held, "and did not take the joystick")
        scroll.scrollTo(0, 0)
        run(20.milliseconds)

        // On the pad, within the dead zone: held, asking for nothing.
        push(stick, 0.5f, 0.47f)
        run(500.milliseconds)
        assertTrue(joystick.state.value.held && joystick.state.value.leftMps == 0.0, "${joystick.state.value}")
        assertTrue(moved() < 0.002, "a resting thumb does not creep: ${moved()} m")

        // Pushed to the rim at once: the wheel speeds climb a ramp to the top speed instead of jumping there.
        val asked = ArrayList<Double>()
        touch(stick, MotionEvent.ACTION_MOVE, 0.5f, 0.0f)
        repeat(12) {
            run(JoystickModel.SEND_PERIOD_MS.milliseconds)
            asked += joystick.state.value.leftMps
        }
        val top = joystick.state.value.maxSpeedMps
        assertTrue(asked.first() <= top / 4, "the first command is a small step: $asked")
        assertTrue(asked.zipWithNext().all { (a, b) -> b >= a && b - a <= JoystickModel.RAMP_MPS_PER_S * 0.05 + 1e-9 }, "then it climbs: $asked")
        assertEquals(top, asked.last(), 1e-9, "and reaches the top speed: $asked")
        assertTrue(moved() > 0.02, "the robot drives")
        touch(stick, MotionEvent.ACTION_UP, 0.5f, 0.0f)
    }

    /** The SDK gave up on the robot's link mid-sweep and the user cancels: the failure is told, the app lives on. */
    @Test
    fun cancellingASweepOnAFailedLinkIsToldNotACrash() = withApp(world = "round") {
        connectRobot()
        val session = model.session.value!!
        click("Calibrate")
        click("Sweep over the line")
        until("sweeping") { shows("Sweeping…") }
        session.robot.close() // as after the SDK gave up reconnecting: every command fails from now on
        until("the link is closed") { session.robot.connection.value is ConnectionState.Closed }
        click("Cancel")
        until("the failure is on screen") { shows("stop the sweep failed") }
        assertTrue(crashed.isEmpty(), "no crash: $crashed")
        click("Follow")
        click("Start")
        until("every action tells its failure") { shows("start line following failed") }
    }

    @Test
    fun calibrationFromWrongValuesGivesValuesWithWhichTheRobotLapsTheTrack() = withApp(world = "round", limit = 150.seconds) {
        connectRobot()
        val robot = emulator.robots.single()
        val session = model.session.value!!
        val start = robot.truePose
        session.robot.settings.lineSensor.calMin.set(List(8) { 3000 })
        session.robot.settings.lineSensor.calMax.set(List(8) { 4000 })
        click("Follow")
        click("Start")
        until("the line is lost with the wrong calibration") { session.robot.lineFollower.followStatus == LineFollowStatus.LOST }
        robot.place(start)

        click("Calibrate")
        screenshot("calibration-start")
        click("Sweep over the line")
        until("the sweep is half way") { shows("Sweeping… 50") || shows("Sweeping… 66") }
        screenshot("calibration-sweeping")
        until("the sweep is measured", 30.seconds) { shows("Measured: every spot sees the line") }
        click("Write to robot")
        until("the robot acknowledged the calibration") { shows("Written: the robot uses it now") }
        screenshot("calibration")
        val written = LineCalibration.of(session.robot)
        assertTrue(written.white.all { it < 200 } && written.black.all { it > 1800 }, "written $written")
        click("Save on robot")
        until("saved") { shows("Saved in the robot's EEPROM") }

        click("Follow")
        click("Start")
        var turned = 0.0
        var prev = polar(robot.truePose)
        var worst = 0.0
        var ms = 0
        while (turned < 2 * PI && ms < 20_000) {
            run(20.milliseconds)
            ms += 20
            val p = robot.truePose
            turned += angle(polar(p) - prev)
            prev = polar(p)
            worst = maxOf(worst, abs(hypot(p.xM - 0.4, p.yM - 0.4) - 0.3))
            if (ms == 4000) {
                val picture = screenshot("follow")
                // The selected colour mode looks selected: a dot in the accent colour, the other mark empty (card white).
                val plain = markCentre(picture, view("Plain: one speed") as RadioButton)
                val segments = markCentre(picture, view("Colour segments: red slows, blue speeds up") as RadioButton)
                assertTrue(near(plain, ACCENT), "the selected radio button has its dot: #%06X at its centre".format(plain and 0xFFFFFF))
                assertTrue(near(segments, Color.WHITE), "the other one has none: #%06X at its centre".format(segments and 0xFFFFFF))
            }
        }
        assertTrue(turned >= 2 * PI, "a lap in 20 s: turned ${turned * 180 / PI} deg")
        assertTrue(worst < 0.004, "the robot stayed on the tape: at most ${worst * 1000} mm off")
        click("Path")
        screenshot("path")
        click("Sensor")
        screenshot("sensor")
    }

    @Test
    fun calibratingByHandReadsWhiteThenBlackAndWritesThem() = withApp(world = "round") {
        connectRobot()
        val robot = emulator.robots.single()
        click("Calibrate")
        click("By hand")
        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0)) // the white floor inside the circle
        click("Read white")
        until("white is read") { shows("Step 2 of 2: black") }
        robot.place(Pose.ofDegrees(0.4, 0.08, 90.0)) // facing the centre: the sensor row lies along the tape
        click("Read black")
        until("black is read") { shows("Measured: every spot sees the line") }
        click("Write to robot")
        until("acknowledged") { shows("Written: the robot uses it now") }
        val written = LineCalibration.of(model.session.value!!.robot)
        assertTrue(written.white.all { it in 90..130 } && written.black.all { it in 1850..1950 }, "written $written")
    }

    @Test
    fun colourModeSlowsOnRedAndSpeedsUpOnBlue() = withApp(world = "colours", limit = 60.seconds) {
        connectRobot()
        val robot = emulator.robots.single()
        click("Follow")
        click("Colour segments: red slows, blue speeds up")
        click("Start")
        val speeds = HashMap<String, MutableList<Double>>()
        var prev = robot.trueWheelDistances
        repeat(140) {
            run(100.milliseconds)
            val w = robot.trueWheelDistances
            val v = ((w.leftM + w.rightM) - (prev.leftM + prev.rightM)) / 2 / 0.1
            prev = w
            val deg = (Math.toDegrees(polar(robot.truePose)) + 360) % 360
            val zone = when { deg in 20.0..60.0 -> "red"; deg in 200.0..240.0 -> "blue"; deg in 100.0..160.0 || deg in 280.0..340.0 -> "black"; else -> null }
            if (zone != null) speeds.getOrPut(zone) { ArrayList() } += v
        }
        val mean = speeds.mapValues { it.value.average() }
        val settings = model.session.value!!.robot.settings.lineFollow
        assertTrue(abs(mean.getValue("red") - settings.redSpeedMps.value) < 0.03, "on red at the red speed ${settings.redSpeedMps.value}: $mean")
        assertTrue(abs(mean.getValue("blue") - settings.blueSpeedMps.value) < 0.05, "on blue at the blue speed ${settings.blueSpeedMps.value}: $mean")
        assertTrue(mean.getValue("red") < mean.getValue("black") && mean.getValue("black") < mean.getValue("blue"), "red < black < blue: $mean")
        assertTrue(find<RadioButton>().isShown)
    }

    @Test
    fun aLinkLostMidDriveIsExplainedAndTheRobotStops() = withApp(world = "round") {
        connectRobot()
        val robot = emulator.robots.single()
        robot.place(Pose.ofDegrees(0.4, 0.4, 0.0))
        click("Drive")
        val stick = find<JoystickCanvas>()
        push(stick, 0.5f, 0.25f)
        run(500.milliseconds)
        robot.disconnectLink()
        until("the app notices the loss") { model.session.value!!.robot.connection.value !is ConnectionState.Connected }
        run(1500.milliseconds) // the robot's link failsafe: 1 s without the host
        val a = robot.trueWheelDistances
        run(1.seconds)
        val b = robot.trueWheelDistances
        assertTrue(abs(b.leftM - a.leftM) + abs(b.rightM - a.rightM) < 0.001, "the robot stopped on its own: $a -> $b")
        assertTrue(shows("lost"), "the user sees the link is lost: ${texts()}")
        assertTrue(shows("Stopped: the link was lost"), "and why the robot stopped: ${texts()}")
        until("the values are marked as old") { shows("Not live: last heard") }
        val measured = view(texts().first { it.startsWith("Wheels measured") }) as android.widget.TextView
        assertEquals(activity.palette.TEXT_SOFT, measured.currentTextColor, "the last measured speeds are greyed")
        screenshot("link-lost")
        robot.reconnectLink()
        until("the link is back", 10.seconds) { model.session.value!!.robot.connection.value == ConnectionState.Connected }
        run(1.seconds)
        val c = robot.trueWheelDistances
        run(1.seconds)
        assertTrue(abs(robot.trueWheelDistances.leftM - c.leftM) < 0.001, "the robot does not drive off again when the link returns")
        assertTrue(!shows("Not live"), "live again: ${texts()}")
    }

    /**
     * "Don't allow" twice: Android 11 and later show no dialog any more (a request is refused at once, and
     * shouldShowRequestPermissionRationale turns false), so "Ask again" would do nothing: the app sends the user to
     * its settings instead, and is ready when they come back with the permission granted.
     */
    @Test
    fun aSecondRefusalSendsTheUserToTheAppSettingsAndBluetoothOffIsExplained() = withApp {
        val nearby = arrayOf(Manifest.permission.BLUETOOTH_SCAN, Manifest.permission.BLUETOOTH_CONNECT)
        shadowOf(app).denyPermissions(*nearby)
        app.bluetoothAccess.refresh()
        launch()
        assertTrue(shows("Android asks you to allow \"Nearby devices\""), texts().toString())
        fun refuse(rationaleAfter: Boolean) {
            val asked = shadowOf(activity).lastRequestedPermission
            assertEquals(nearby.toList(), asked.requestedPermissions.toList())
            nearby.forEach { shadowOf(app.packageManager).setShouldShowRequestPermissionRationale(it, rationaleAfter) }
            activity.onRequestPermissionsResult(asked.requestCode, asked.requestedPermissions, intArrayOf(-1, -1))
        }
        click("Allow Bluetooth")
        refuse(rationaleAfter = true) // the first "Don't allow": Android will ask again
        run(20.milliseconds)
        assertTrue(shows("Bluetooth permission refused"), texts().toString())
        click("Ask again")
        refuse(rationaleAfter = false) // the second: Android asks no more
        run(20.milliseconds)
        assertTrue(shows("Android no longer asks"), texts().toString())
        screenshot("permission-refused")
        click("Open settings")
        val settings = shadowOf(activity).nextStartedActivity
        assertEquals(Settings.ACTION_APPLICATION_DETAILS_SETTINGS, settings.action)
        assertEquals("package:org.pocketbot.android", settings.data.toString())

        // Allowed in the settings, but Bluetooth is off: back in the app, it asks to turn it on.
        shadowOf(app).grantPermissions(*nearby)
        shadowOf(BluetoothAdapter.getDefaultAdapter()).setEnabled(false)
        controller.pause().stop().start().resume()
        run(20.milliseconds)
        assertTrue(shows("Bluetooth is off"), texts().toString())
        click("Turn Bluetooth on")
        assertEquals(BluetoothAdapter.ACTION_REQUEST_ENABLE, shadowOf(activity).nextStartedActivityForResult.intent.action)
        // Robots are still there over the network (here: the emulator in this process).
        click("Find robots")
        until("the emulated robot is found without Bluetooth") { model.found.value.isNotEmpty() }
        screenshot("robots")
    }

    @Test
    fun rotatingThePhoneKeepsTheConnection() = withApp {
        connectRobot()
        val session = model.session.value!!
        click("Follow")
        click("Start")
        run(1.seconds)
        val before = activity
        rotate()
        assertTrue(before !== activity, "a new Activity")
        assertEquals(session, model.session.value, "the connection outlived the Activity")
        assertEquals(ConnectionState.Connected, session.robot.connection.value)
        assertEquals(Screen.FOLLOW, model.screen.value)
        assertEquals(LineFollowStatus.FOLLOWING, session.robot.lineFollower.followStatus, "the robot kept following")
    }

    private fun near(colour: Int, expected: Int): Boolean =
        abs(Color.red(colour) - Color.red(expected)) + abs(Color.green(colour) - Color.green(expected)) + abs(Color.blue(colour) - Color.blue(expected)) < 60

    private fun polar(p: Pose) = atan2(p.yM - 0.4, p.xM - 0.4)
    private fun angle(d: Double): Double = when { d > PI -> d - 2 * PI; d < -PI -> d + 2 * PI; else -> d }

    private companion object {
        /** The theme's accent (res/values/colors.xml), which a checked radio button is drawn in. */
        val ACCENT = Color.rgb(0xF2, 0x8C, 0x28)
    }
}
