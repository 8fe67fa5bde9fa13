@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.async
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.launch
import kotlinx.coroutines.test.advanceTimeBy
import kotlinx.coroutines.test.currentTime
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.Goodbye
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.SetRole
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.StateEncoders
import org.pocketbot.protocol.StateLocomotion
import org.pocketbot.protocol.Stop
import org.pocketbot.protocol.UpdateSettings
import kotlin.math.PI
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertIs
import kotlin.test.assertNotNull
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/** One host drives, the others watch; take-over, goodbye, a restart's truth and quick reconnects, against a scripted robot. */
class DrivingTest {
    @Test
    fun aHostThatAsksToDriveAFreeRobotDrivesIt() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, RobotOptions(testOptions()) { hostLabel = "test@host" })
        assertEquals(Driving(true, "test@host", DriverChange.CLAIMED), robot.driving.value)
        assertEquals(SetRole(HostRole.DRIVE.code, "test@host"), peer.received.map { it.second }.filterIsInstance<SetRole>().single())
        robot.close()
    }

    @Test
    fun aWatchingHostsCommandsFailAtOnceNamingTheDriverWhileReadsAndStopGoOn() = runTest {
        val peer = ScriptedRobot().apply { otherDriver = "panel@lab-pc" }
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        assertEquals(Driving(false, "panel@lab-pc", DriverChange.NONE), robot.driving.value)
        val sent = peer.received.size
        val e = assertFailsWith<NotDriverException> { robot.locomotion.enqueue(Movement.Straight(0.1, 0.1)) }
        assertEquals("Scripted is driven by panel@lab-pc", e.message)
        assertEquals("panel@lab-pc", e.driver)
        assertFailsWith<NotDriverException> { robot.settings.linePid.kp.set(2.0) }
        assertFailsWith<NotDriverException> { robot.reflector.set(SyncMode.REDUCED, 5.milliseconds) }
        assertFailsWith<NotDriverException> { robot.locomotion.setWheelSpeeds(0.1, 0.1) }
        assertEquals(sent, peer.received.size, "nothing was sent for them")
        assertTrue(peer.executed.none { it is SetSync }, "a watcher does not change the driver's sync mode")
        assertEquals(SyncMode.FULL, robot.reflector.mode.value, "it takes the robot's")
        robot.locomotion.stop()
        assertIs<Stop>(peer.executed.last(), "anyone may stop the robot")
        robot.close()
    }

    @Test
    fun takingOverDrivesAndAReconnectAsksToDriveNotToTakeOverAgain() = runTest {
        val peer = ScriptedRobot().apply { otherDriver = "panel@lab-pc" }
        val robot = connect(peer, RobotOptions(testOptions()) { hostLabel = "cli@lab-pc" })
        val events = async { robot.events.first() }
        runCurrent()
        val now = robot.takeOver()
        assertEquals(Driving(true, "cli@lab-pc", DriverChange.TAKEN_OVER), now)
        assertEquals(now, (events.await() as RobotEvent.DriverChanged).driving)
        robot.locomotion.enqueue(Movement.Straight(0.1, 0.1))
        assertIs<MoveStraight>(peer.executed.last())
        peer.takenOverBy("phone")
        peer.disconnect()
        awaitReconnect(robot)
        assertEquals(HostRole.DRIVE.code, peer.received.map { it.second }.filterIsInstance<SetRole>().last().role)
        assertEquals(Driving(false, "phone", DriverChange.NONE), robot.driving.value, "it watches: the phone took it meanwhile")
        robot.close()
    }

    @Test
    fun aHostTakenOverIsToldAndItsNextCommandFailsAsWatched() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val events = mutableListOf<RobotEvent>()
        backgroundScope.launch(runtime()) { robot.events.collect { events += it } }
        runCurrent()
        peer.takenOverBy("panel@lab-pc")
        runCurrent()
        val changed = assertIs<RobotEvent.DriverChanged>(events.single())
        assertTrue(changed.taken, "taken from this host")
        assertEquals(Driving(false, "panel@lab-pc", DriverChange.TAKEN_OVER), robot.driving.value)
        assertEquals(ConnectionState.Connected, robot.connection.value, "taken over is no lost link")
        val e = assertFailsWith<NotDriverException> { robot.locomotion.enqueue(Movement.Straight(0.1, 0.1)) }
        assertEquals("Scripted is driven by panel@lab-pc", e.message)
        robot.close()
    }

    @Test
    fun aCommandTheRobotRefusesAfterATakeOverThisHostDidNotHearOfFailsAsNotDriven() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        peer.dropOutgoingIf = { it is org.pocketbot.protocol.Driver } // the robot's word is lost on the way
        peer.takenOverBy("panel@lab-pc")
        val e = assertFailsWith<NotDriverException> { robot.settings.linePid.kp.set(3.0) }
        assertEquals("Scripted is not driven by this host", e.message)
        robot.close()
    }

    @Test
    fun disconnectSaysGoodbyeAndTheRobotFinishesOrDropsAsAsked() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.locomotion.enqueue(Movement.Straight(0.5, 0.1))
        assertTrue(robot.disconnect(QueueOnLeave.FINISH), "acknowledged")
        assertEquals(Goodbye(QueueOnLeave.FINISH.ordinal), peer.executed.last())
        assertEquals(1, peer.queue.size, "the movement stays queued on the robot")
        assertFalse(robot.disconnect(QueueOnLeave.DROP), "closed already: nothing to say")

        val again = connect(peer)
        again.disconnect(QueueOnLeave.DROP)
        assertEquals(Goodbye(QueueOnLeave.DROP.ordinal), peer.executed.last())
    }

    @Test
    fun closeSaysGoodbyeWithoutWaiting() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        robot.close()
        runCurrent()
        assertEquals(Goodbye(QueueOnLeave.FINISH.ordinal), peer.received.last().second)
        assertFalse(peer.connected, "and closed the link")
    }

    @Test
    fun aRobotThatRestartedIsReportedAndItsCutMovementEndsLostWithWhatTheHostSaw() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer, testOptions(syncMode = SyncMode.FULL))
        val handle = robot.locomotion.enqueue(Movement.Straight(1.0, 0.1))
        val events = mutableListOf<RobotEvent>()
        backgroundScope.launch(runtime()) { robot.events.collect { events += it } }
        // The robot runs it and reports its encoders: 100 pulses a wheel at 40 per 9 mm wheel turn, about 70.7 mm.
        val running = StateLocomotion(org.pocketbot.protocol.LocoMode.MOVEMENT, 1, handle.id, 0)
        peer.sendState(peer.state.withTime(46_000).with(encoders = StateEncoders(0, 0), locomotion = running))
        peer.sendState(peer.state.withTime(46_700).with(encoders = StateEncoders(100, 100), locomotion = running))
        runCurrent()
        // It restarts (time back to 0, queue and log gone); its hello at reset is lost with the link.
        peer.dropOutgoing = 1
        peer.reset()
        peer.disconnect()
        awaitReconnect(robot)
        runCurrent()
        val restarted = assertIs<RobotEvent.Restarted>(events.singleOrNull { it is RobotEvent.Restarted }, "events: $events, received ${peer.received.map { it.second::class.simpleName }}")
        assertEquals(46_700, restarted.lastSeenTimeMs)
        val result = handle.await()
        assertEquals(MovementOutcome.LOST, result.outcome)
        val seen = 100 * PI * 0.009 / 40
        assertEquals(seen, assertNotNull(result.done), 1e-6, "what the host saw")
        assertTrue(result.detail.startsWith("the robot restarted"), result.detail)
        robot.close()
    }

    @Test
    fun aLinkThatComesBackIsReconnectedWithinTheQuickRetriesWhileTheFailsafeWaits() = runTest {
        val peer = ScriptedRobot()
        val policy = ReconnectPolicy() // what users get
        val robot = connect(peer, testOptions(reconnect = policy))
        peer.refuseOpens = Int.MAX_VALUE
        peer.disconnect()
        advanceTimeBy(500) // half a second down, as the failsafe's 1 s still waits
        peer.refuseOpens = 0
        val back = currentTime
        robot.connection.first { it == ConnectionState.Connected }
        assertTrue(currentTime - back <= policy.initialDelay.inWholeMilliseconds, "back after ${currentTime - back} ms")
        // Long outages back off: far fewer attempts per second after the quick phase.
        peer.refuseOpens = Int.MAX_VALUE
        peer.disconnect()
        advanceTimeBy(2_000)
        val quick = peer.opens
        advanceTimeBy(10_000)
        assertTrue(peer.opens - quick <= 15, "${peer.opens - quick} attempts in 10 s after the quick phase")
        assertTrue(quick >= 60, "$quick attempts in the first 2 s")
        robot.close()
    }

    @Test
    fun aRefusedConnectSaysThatEveryLinkIsInUse() = runTest {
        val peer = ScriptedRobot()
        peer.answersHello = false
        val opening = async {
            assertFailsWith<ConnectFailedException> { connect(peer, RobotOptions(testOptions()) { helloAttempts = 1 }) }
        }
        runCurrent()
        peer.send(org.pocketbot.protocol.Error(org.pocketbot.protocol.ErrorCode.NO_FREE_LINK.code, 0, 0, 3))
        peer.disconnect()
        val e = opening.await()
        assertTrue(e.message!!.contains("all 3 host links of Scripted are in use by other hosts"), e.message)
        assertTrue(peer.received.none { it.second is UpdateSettings })
    }
}
