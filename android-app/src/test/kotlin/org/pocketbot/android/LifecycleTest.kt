package org.pocketbot.android

import android.Manifest
import android.app.ForegroundServiceStartNotAllowedException
import android.app.Notification
import android.content.ComponentName
import android.content.Intent
import android.content.pm.ServiceInfo
import android.os.Build
import android.view.WindowManager
import org.junit.After
import org.junit.Test
import org.junit.runner.RunWith
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.protocol.LocoMode
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.LineFollowStatus
import org.robolectric.Robolectric
import org.robolectric.Shadows.shadowOf
import org.robolectric.android.controller.ServiceController
import org.robolectric.annotation.Config
import org.robolectric.annotation.Implementation
import org.robolectric.annotation.Implements
import org.robolectric.shadows.ShadowContextImpl
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * Android 12 on (API 31): an app in the background may not start a foreground service (Robolectric lets it; phones
 * throw [ForegroundServiceStartNotAllowedException]). [inBackground] says where the app is.
 */
@Implements(className = ShadowContextImpl.CLASS_NAME)
class BackgroundStartRule : ShadowContextImpl() {
    @Implementation
    override fun startForegroundService(service: Intent): ComponentName? {
        if (inBackground && Build.VERSION.SDK_INT >= Build.VERSION_CODES.S) {
            throw ForegroundServiceStartNotAllowedException("startForegroundService() not allowed due to mAllowStartForeground false")
        }
        return super.startForegroundService(service)
    }

    companion object {
        @Volatile var inBackground = false
    }
}

/**
 * The app's life around a connected robot, as Android drives it (ActivityController, ServiceController, Back as a key
 * event through the window), against the emulator's real firmware: the foreground service runs exactly while a robot
 * is connected, with a notification whose Stop button stops the robot; Back and swiping the app away from the recent
 * apps stop the robot (ground truth); the screen stays on while the robot drives.
 */
@RunWith(org.robolectric.RobolectricTestRunner::class)
@Config(sdk = [35], application = TestApp::class, qualifiers = "w360dp-h760dp-xhdpi", shadows = [BackgroundStartRule::class, PlatformBluetoothDevice::class])
class LifecycleTest {
    @After
    fun foreground() {
        BackgroundStartRule.inBackground = false
    }

    @Test
    fun theForegroundServiceRunsWhileARobotIsConnectedAndEndsItselfWhenNot() = withApp {
        launch()
        assertNull(shadowOf(app).nextStartedService, "no robot, no service")
        connectRobot()
        val service = startedService()
        val notification = assertNotNull(shadowOf(service).lastForegroundNotification, "the service is in the foreground")
        assertEquals("Connected to PocketBot-1", notification.extras.getString(Notification.EXTRA_TITLE))
        assertEquals(ServiceInfo.FOREGROUND_SERVICE_TYPE_CONNECTED_DEVICE, service.foregroundServiceType)
        val open = shadowOf(notification.contentIntent).savedIntent
        assertEquals(MainActivity::class.java.name, open.component?.className, "the notification leads back to the app")

        // A lost link is no reason to stop: the SDK reconnects in the background, the service keeps the process for it.
        val robot = emulator.robots.single()
        robot.disconnectLink()
        until("the loss is noticed") { model.session.value!!.robot.connection.value != ConnectionState.Connected }
        run(500.milliseconds)
        assertFalse(shadowOf(service).isStoppedBySelf, "the service stays while the robot reconnects")
        robot.reconnectLink()
        until("reconnected") { model.session.value!!.robot.connection.value == ConnectionState.Connected }

        click("Robots")
        click("Disconnect")
        until("disconnected") { model.session.value == null }
        until("the service ended itself") { shadowOf(service).isStoppedBySelf }
        assertTrue(shadowOf(service).isForegroundStopped, "and left the foreground")
        assertNull(shadowOf(app).nextStoppedService, "never stopped from outside (Android ends an app for that before it went foreground)")

        // Connected again: the service again, named after the robot.
        click("Connect")
        until("connected again") { model.session.value != null }
        assertEquals("PocketBot-1", shadowOf(app).nextStartedService?.getStringExtra("robot"))
    }

    @Test
    fun aServiceStartedAndNoLongerWantedBeforeItRanGoesForegroundThenEndsWithoutACrash() = withApp {
        connectRobot()
        val intent = assertNotNull(shadowOf(app).nextStartedService)
        click("Robots")
        click("Disconnect") // before Android got round to starting the service
        until("disconnected") { model.session.value == null }
        val service = Robolectric.buildService(ConnectionService::class.java, intent).create().startCommand(0, 1).get()
        run(50.milliseconds)
        assertEquals(ServiceInfo.FOREGROUND_SERVICE_TYPE_CONNECTED_DEVICE, service.foregroundServiceType, "it went to the foreground first, as Android demands")
        assertTrue(shadowOf(service).isStoppedBySelf && shadowOf(service).isForegroundStopped, "then ended itself")
        assertNull(shadowOf(app).nextStoppedService)
    }

    @Test
    fun aServiceRefusedInTheBackgroundStartsOnceTheAppIsBack() = withApp {
        launch()
        click("Find robots")
        until("the robot is found") { model.found.value.isNotEmpty() }
        click("Connect")
        controller.pause().stop() // the user switched to another app while it connects
        BackgroundStartRule.inBackground = true
        until("connected in the background") { model.session.value != null }
        run(100.milliseconds)
        assertNull(shadowOf(app).nextStartedService, "Android refused the service in the background")
        BackgroundStartRule.inBackground = false
        controller.start().resume() // back to the app
        run(50.milliseconds)
        assertEquals("PocketBot-1", shadowOf(app).nextStartedService?.getStringExtra("robot"), "started now")
    }

    /** Android 12 shows the notification without asking; 13 and later only if the user allows it. */
    @Test
    @Config(sdk = [31, 35])
    fun theNotificationIsAskedForOnAndroid13AndItsStopButtonStopsTheRobot() = withApp {
        connectRobot()
        val asked = shadowOf(activity).lastRequestedPermission
        if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.TIRAMISU) {
            assertEquals(listOf(Manifest.permission.POST_NOTIFICATIONS), asked?.requestedPermissions?.toList(), "asked when a robot connects")
            activity.onRequestPermissionsResult(asked!!.requestCode, asked.requestedPermissions, intArrayOf(-1))
            run(20.milliseconds)
            assertTrue(shows("Notifications are off"), "a refusal is explained: ${texts()}")
        } else {
            assertNull(asked, "no notification permission before Android 13")
        }
        val service = startedService()
        val session = model.session.value!!
        val robot = emulator.robots.single()
        startFollowing()
        until("the screen is kept on while the robot drives") { keepsScreenOn() }
        controller.pause().stop() // the app in the background; the robot follows the line

        val stop = shadowOf(service).lastForegroundNotification.actions.single { it.title == "Stop robot" }
        stop.actionIntent.send()
        val delivered = assertNotNull(shadowOf(app).nextStartedService, "the notification's button reaches the service")
        Robolectric.buildService(ConnectionService::class.java, delivered).create().startCommand(0, 2)
        assertStopped(robot)
        assertEquals(ConnectionState.Connected, session.robot.connection.value, "stopped, still connected")
        controller.start().resume()
        until("the screen may sleep again") { !keepsScreenOn() }
    }

    @Test
    fun swipingTheAppAwayFromTheRecentAppsStopsTheRobot() = withApp {
        connectRobot()
        val service = startedService()
        val session = model.session.value!!
        val robot = emulator.robots.single()
        startFollowing()
        controller.pause().stop() // the recent apps screen: the app goes to the background ...
        run(1.seconds)
        assertEquals(ConnectionState.Connected, session.robot.connection.value, "... and stays connected there")
        assertEquals(LocoMode.LINE_FOLLOW, robot.state().locomotion.mode)

        service.onTaskRemoved(Intent(app, MainActivity::class.java)) // ... and the user swipes it away
        until("the robot is disconnected") { model.session.value == null && session.robot.connection.value is ConnectionState.Closed }
        until("the service ends with the app") { shadowOf(service).isStoppedBySelf }
        assertStopped(robot)
    }

    /**
     * Android 12 and later move a launcher activity to the background on Back instead of finishing it: Back must stop
     * the robot itself. Pressed as a key into the window: Android 12 hands it to the Activity (onBackPressed), 13 and
     * later to the window's top OnBackInvokedCallback.
     */
    @Test
    @Config(sdk = [31, 35])
    fun backWithARobotDrivingStopsItAndAsksToLeave() = withApp {
        connectRobot()
        val session = model.session.value!!
        val robot = emulator.robots.single()
        startFollowing()

        pressBack()
        assertStopped(robot)
        assertFalse(activity.isFinishing, "not left yet: the user is asked")
        val ask = dialog()
        assertTrue(shadowOf(ask).message.contains("PocketBot-1 is stopped"), "${shadowOf(ask).message}")
        ask.getButton(android.app.AlertDialog.BUTTON_NEGATIVE).performClick() // Stay
        run(300.milliseconds)
        assertEquals(ConnectionState.Connected, session.robot.connection.value, "staying keeps the connection")

        click("Start")
        until("following again") { session.robot.lineFollower.followStatus == LineFollowStatus.FOLLOWING }
        pressBack()
        dialog().getButton(android.app.AlertDialog.BUTTON_POSITIVE).performClick() // Disconnect and leave
        until("the robot is disconnected") { model.session.value == null && session.robot.connection.value is ConnectionState.Closed }
        assertTrue(activity.isFinishing, "and the app is left")
        assertStopped(robot)
    }

    /** Starts line following on the Follow screen, as a person does, and waits until the robot follows the line. */
    private suspend fun AppHarness.startFollowing() {
        click("Follow")
        click("Start")
        until("following the line") { model.session.value!!.robot.lineFollower.followStatus == LineFollowStatus.FOLLOWING }
    }

    private fun AppHarness.keepsScreenOn() = activity.window.attributes.flags and WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON != 0

    /** The service Android starts for the intent the app asked for, created and started as Android does. */
    private fun AppHarness.startedService(): ConnectionService {
        val intent = assertNotNull(shadowOf(app).nextStartedService, "a robot is connected: the app starts its service")
        assertEquals(ConnectionService::class.java.name, intent.component?.className)
        assertEquals("PocketBot-1", intent.getStringExtra("robot"))
        val controller: ServiceController<ConnectionService> = Robolectric.buildService(ConnectionService::class.java, intent)
        return controller.create().startCommand(0, 1).get()
    }

    /** The robot was stopped by the app's stop command (not only by its link failsafe) and stands. */
    private suspend fun AppHarness.assertStopped(robot: RobotHandle) {
        until("the robot is stopped by a command", 2.seconds) { robot.state().locomotion.mode == LocoMode.IDLE }
        run(300.milliseconds)
        val a = robot.trueWheelDistances
        run(1.seconds)
        val b = robot.trueWheelDistances
        assertTrue(abs(b.leftM - a.leftM) + abs(b.rightM - a.rightM) < 0.001, "the robot stands: $a -> $b")
    }
}
