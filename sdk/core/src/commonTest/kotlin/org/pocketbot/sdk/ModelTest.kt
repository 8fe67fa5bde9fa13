package org.pocketbot.sdk

import org.pocketbot.protocol.ProtocolInfo
import kotlin.test.Test
import kotlin.test.assertEquals
import org.pocketbot.protocol.RobotState as WireState

/** The SDK's model of the state (generated from the schema) against the wire struct it is mapped from, field by field. */
class ModelTest {
    /** A state whose every byte differs, so that two fields swapped by the mapping cannot read the same. */
    private val wire = WireState.decode(ByteArray(ProtocolInfo.STATE_SIZE) { (it * 37 + 11).toByte() }, 0)
    private val model = wire.toModel()

    @Test
    fun everyFieldReadsAsOnTheWire() {
        val w = wire
        val m = model
        assertEquals(listOf(w.time.timeMs, w.time.tickMaxUs, w.time.overruns, w.time.lastOverrunMs),
            listOf(m.time.timeMs, m.time.tickMaxUs, m.time.overruns, m.time.lastOverrunMs))
        assertEquals(listOf(w.encoders.left, w.encoders.right), listOf(m.encoders.left, m.encoders.right))
        assertEquals(listOf(w.wheels.speedLeftMmps, w.wheels.speedRightMmps, w.wheels.pwmLeft, w.wheels.pwmRight),
            listOf(m.wheels.speedLeftMmps, m.wheels.speedRightMmps, m.wheels.pwmLeft, m.wheels.pwmRight))
        assertEquals(w.line.raw, m.line.raw)
        assertEquals(w.line.position, m.line.position)
        assertEquals(w.line.flags and 0x03, m.line.flags.sumOf { it.mask })
        assertEquals(w.lineFollow.status.name, m.lineFollow.status.name)
        assertEquals(w.lineFollow.segment.name, m.lineFollow.segment.name)
        for ((ws, ms) in listOf(w.proximity.front to m.proximity.front, w.proximity.rear to m.proximity.rear)) {
            assertEquals(ws.flags and 0x03, ms.flags.sumOf { it.mask })
            assertEquals(ws.robotId, ms.robotId)
            assertEquals(ws.robotLed.name, ms.robotLed.name)
            assertEquals(ws.distance.name, ms.distance.name)
        }
        assertEquals(listOf(w.colour.red, w.colour.green, w.colour.blue, w.colour.clear),
            listOf(m.colour.red, m.colour.green, m.colour.blue, m.colour.clear))
        assertEquals(w.colour.detected.name, m.colour.detected.name)
        assertEquals(listOf(w.accel.xMg, w.accel.yMg, w.accel.zMg), listOf(m.accel.xMg, m.accel.yMg, m.accel.zMg))
        assertEquals(listOf(w.power.batteryMv, w.power.currentMa, w.power.mcuTempDc),
            listOf(m.power.batteryMv, m.power.currentMa, m.power.mcuTempDc))
        assertEquals(w.indicators.led and 0x0F, m.indicators.led.sumOf { it.mask })
        assertEquals(w.indicators.irPower, m.indicators.irPower)
        assertEquals(w.locomotion.mode.name, m.locomotion.mode.name)
        assertEquals(listOf(w.locomotion.queueLength, w.locomotion.currentId, w.locomotion.finishedId),
            listOf(m.locomotion.queueLength, m.locomotion.currentId, m.locomotion.finishedId))
        assertEquals(w.track.status.name, m.track.status.name)
        assertEquals(listOf(w.track.token, w.track.tokenVisits, w.track.metId), listOf(m.track.token, m.track.tokenVisits, m.track.metId))
        with(w.errors) {
            assertEquals(listOf(crc, framing, rejected, rxOverflow, txDropped, btWire, btTimeouts, btResets, btDropped), m.errors.let {
                listOf(it.crc, it.framing, it.rejected, it.rxOverflow, it.txDropped, it.btWire, it.btTimeouts, it.btResets, it.btDropped)
            })
        }
    }

    @Test
    fun everyStateFieldHasAValueAndTheModelComparesByValue() {
        assertEquals(StateFields.all.size, StateFields.all.map { it.name }.toSet().size)
        StateFields.all.forEach { it.of(model) }
        assertEquals(model, wire.toModel())
        assertEquals(model.hashCode(), wire.toModel().hashCode())
    }

    @Test
    fun everyWireCodeMapsToTheValueOfTheSameName() {
        fun <W : Enum<W>, M : Enum<M>> check(wire: List<W>, code: (W) -> Int, model: (Int) -> M, unknown: M) =
            wire.forEach { w -> assertEquals(if (code(w) < 0) unknown.name else w.name, model(code(w)).name, "$w") }
        check(org.pocketbot.protocol.SyncMode.entries, { it.code }, SyncMode::fromCode, SyncMode.UNKNOWN)
        check(org.pocketbot.protocol.LocoMode.entries, { it.code }, LocoMode::fromCode, LocoMode.UNKNOWN)
        check(org.pocketbot.protocol.LineFollowStatus.entries, { it.code }, LineFollowStatus::fromCode, LineFollowStatus.UNKNOWN)
        check(org.pocketbot.protocol.Colour.entries, { it.code }, Colour::fromCode, Colour.UNKNOWN)
        check(org.pocketbot.protocol.ColourMode.entries, { it.code }, ColourMode::fromCode, ColourMode.UNKNOWN)
        check(org.pocketbot.protocol.IrLed.entries, { it.code }, IrLed::fromCode, IrLed.UNKNOWN)
        check(org.pocketbot.protocol.Side.entries, { it.code }, Side::fromCode, Side.UNKNOWN)
        check(org.pocketbot.protocol.DistanceClass.entries, { it.code }, DistanceClass::fromCode, DistanceClass.UNKNOWN)
        check(org.pocketbot.protocol.ErrorCode.entries, { it.code }, ErrorCode::fromCode, ErrorCode.UNKNOWN)
        check(org.pocketbot.protocol.DebugModule.entries, { it.code }, DebugModule::fromCode, DebugModule.UNKNOWN)
        check(org.pocketbot.protocol.TrackStatus.entries, { it.code }, TrackStatus::fromCode, TrackStatus.UNKNOWN)
        // A movement outcome this SDK does not know is one it has no record of.
        check(org.pocketbot.protocol.MovementOutcome.entries, { it.code }, MovementOutcome::fromCode, MovementOutcome.LOST)
        assertEquals(MovementOutcome.LOST, MovementOutcome.fromCode(200))
    }

    @Test
    fun flagBitsReadAsSetsAndUnknownBitsAreLeftOut() {
        assertEquals(setOf(LineFlag.SEEN, LineFlag.LOST), LineFlag.of(0xFF))
        assertEquals(emptySet(), LineFlag.of(0))
        assertEquals(setOf(LedFlag.ALIVE, LedFlag.TOKEN), LedFlag.of(0x09))
        assertEquals(setOf(ProximityFlag.ROBOT), ProximityFlag.of(0x02))
    }
}
