@file:OptIn(kotlinx.coroutines.ExperimentalCoroutinesApi::class)

package org.pocketbot.sdk

import kotlinx.coroutines.async
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.flow.take
import kotlinx.coroutines.flow.toList
import kotlinx.coroutines.test.runCurrent
import kotlinx.coroutines.test.runTest
import org.pocketbot.protocol.DistanceClass as WireDistance
import org.pocketbot.protocol.IrLed as WireLed
import org.pocketbot.protocol.IrReceived
import org.pocketbot.protocol.IrSend
import org.pocketbot.protocol.ProximitySide
import org.pocketbot.protocol.StateProximity
import org.pocketbot.protocol.StateTime
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals

class ProximityTest {
    @Test
    fun encountersReportNewAndChangedSightings() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val got = async { robot.proximity.encounters.take(2).toList() }
        runCurrent()
        val nobody = ProximitySide(0, 0, WireLed.FRONT, WireDistance.NONE)
        fun state(t: Long, front: ProximitySide) = WIRE_EMPTY.with(time = StateTime(t, 0, 0, 0), proximity = StateProximity(front, nobody))
        peer.sendState(state(1, ProximitySide(2, 3, WireLed.REAR, WireDistance.FAR)))
        peer.sendState(state(2, ProximitySide(2, 3, WireLed.REAR, WireDistance.FAR))) // unchanged
        peer.sendState(state(3, ProximitySide(3, 3, WireLed.REAR, WireDistance.NEAR))) // closer, obstacle too
        val encounters = got.await()
        assertEquals(Encounter(3, Side.FRONT, IrLed.REAR, DistanceClass.FAR, 1), encounters[0])
        assertEquals(Encounter(3, Side.FRONT, IrLed.REAR, DistanceClass.NEAR, 3), encounters[1])
        assertEquals(true, robot.proximity.obstacleFront)
        robot.close()
    }

    @Test
    fun messagesInAndOut() = runTest {
        val peer = ScriptedRobot()
        val robot = connect(peer)
        val msg = async { robot.proximity.messages.first() }
        runCurrent()
        peer.send(IrReceived(4, Side.REAR.code, IrLed.FRONT.code, 80, byteArrayOf(1, 2, 3)))
        val m = msg.await()
        assertEquals(4, m.senderId)
        assertEquals(Side.REAR, m.side)
        assertContentEquals(byteArrayOf(1, 2, 3), m.payload)
        robot.proximity.send(byteArrayOf(9, 9), powerPercent = 50)
        assertEquals(IrSend(50, byteArrayOf(9, 9)), peer.executed.last())
        robot.close()
    }
}
