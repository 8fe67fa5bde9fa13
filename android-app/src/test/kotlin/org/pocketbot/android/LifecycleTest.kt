package org.pocketbot.android

import android.app.Notification
import android.content.Intent
import android.content.pm.ServiceInfo
import org.junit.Test
import org.junit.runner.RunWith
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.protocol.LineFollowStatus
import org.pocketbot.protocol.LocoMode
import org.pocketbot.sdk.ConnectionState
import org.robolectric.Robolectric
import org.robolectric.Shadows.shadowOf
import org.robolectric.android.controller.ServiceController
import org.robolectric.annotation.Config
import kotlin.math.abs
import kotlin.test.assertEquals
import kotlin.test.assertNotNull
import kotlin.test.assertNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * The app's life around a connected robot, as Android drives it (ActivityController, ServiceController), against the
 * emulator's real firmware: the foreground service runs exactly while a robot is connected, and closing the app, by
 * backing out of it or by swiping it away from the recent apps, stops the robot (ground truth) and disconnects it.
 */
@RunWith(org.robolectric.RobolectricTestRunner::class)
@Config(sdk = [34], application = TestApp::class, qualifiers = "w360dp-h760dp-xhdpi")
class LifecycleTest {
    @Test
    fun theForegroundServiceRunsWhileARobotIsConnectedAndStopsWhenNot() = withApp {
        launch()
        assertNull(shadowOf(app).nextStartedService, "no robot, no service")
        assertNull(shadowOf(app).nextStoppedService, "and none to stop")
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
        assertNull(shadowOf(app).nextStoppedService, "the service stays while the robot reconnects")
        robot.reconnectLink()
        until("reconnected") { model.session.value!!.robot.connection.value == ConnectionState.Connected }

        click("Robots")
        click("Disconnect")
        until("disconnected") { model.session.value == null }
        val stopped = assertNotNull(shadowOf(app).nextStoppedService, "no robot connected: the service is stopped")
        assertEquals(ConnectionService::class.java.name, stopped.component?.className)

        // Connected again: the service again, named after the robot.
        click("Connect")
        until("connected again") { model.session.value != null }
        assertEquals("PocketBot-1", shadowOf(app).nextStartedService?.getStringExtra("robot"))
    }

    @Test
    fun swipingTheAppAwayFromTheRecentAppsStopsTheRobot() = withApp {
        connectRobot()
        val service = startedService()
        val session = model.session.value!!
        val robot = emulator.robots.single()
        click("Follow")
        click("Start")
        until("following the line") { session.robot.lineFollower.followStatus == LineFollowStatus.FOLLOWING }
        controller.pause().stop() // the recent apps screen: the app goes to the background ...
        run(1.seconds)
        assertEquals(ConnectionState.Connected, session.robot.connection.value, "... and stays connected there")
        assertEquals(LocoMode.LINE_FOLLOW, robot.state().locomotion.mode)

        service.onTaskRemoved(Intent(app, MainActivity::class.java)) // ... and the user swipes it away
        until("the robot is disconnected") { model.session.value == null && session.robot.connection.value is ConnectionState.Closed }
        assertTrue(shadowOf(service).isStoppedBySelf, "the service ends with the app")
        assertStoppedByTheApp(robot)
    }

    @Test
    fun backingOutOfTheAppStopsTheRobot() = withApp {
        connectRobot()
        startedService()
        val session = model.session.value!!
        val robot = emulator.robots.single()
        click("Follow")
        click("Start")
        until("following the line") { session.robot.lineFollower.followStatus == LineFollowStatus.FOLLOWING }
        closeApp() // Back: Android finishes the Activity and destroys it
        assertTrue(activity.isFinishing)
        until("the robot is disconnected") { model.session.value == null && session.robot.connection.value is ConnectionState.Closed }
        assertNotNull(shadowOf(app).nextStoppedService, "the service is stopped")
        assertStoppedByTheApp(robot)
    }

    /** The service Android starts for the intent the app asked for, created and started as Android does. */
    private fun AppHarness.startedService(): ConnectionService {
        val intent = assertNotNull(shadowOf(app).nextStartedService, "a robot is connected: the app starts its service")
        assertEquals(ConnectionService::class.java.name, intent.component?.className)
        assertEquals("PocketBot-1", intent.getStringExtra("robot"))
        val controller: ServiceController<ConnectionService> = Robolectric.buildService(ConnectionService::class.java, intent)
        return controller.create().startCommand(0, 1).get()
    }

    /** The robot was stopped by the app's stop command (not only by its link failsafe) and stands. */
    private suspend fun AppHarness.assertStoppedByTheApp(robot: RobotHandle) {
        run(300.milliseconds)
        assertEquals(LocoMode.IDLE, robot.state().locomotion.mode, "stopped by the app before it disconnected, not left to the failsafe")
        val a = robot.trueWheelDistances
        run(1.seconds)
        val b = robot.trueWheelDistances
        assertTrue(abs(b.leftM - a.leftM) + abs(b.rightM - a.rightM) < 0.001, "the robot stands: $a -> $b")
    }
}
