package org.pocketbot.sdk.internal

import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.RobotState as WireState
import org.pocketbot.protocol.StateReduced
import org.pocketbot.sdk.LineFlag
import org.pocketbot.sdk.RobotState
import org.pocketbot.sdk.toModel

/** The state before the first state packet: all zero, robot time 0. */
internal val EMPTY_STATE: RobotState = WireState.decode(ByteArray(ProtocolInfo.STATE_SIZE), 0).toModel()

/** [this] state with the parts a reduced packet carries replaced; everything else stays as last seen. */
internal fun RobotState.merge(r: StateReduced): RobotState = RobotState(
    time = RobotState.Time(timeMs = r.timeMs, tickMaxUs = time.tickMaxUs, overruns = time.overruns, lastOverrunMs = time.lastOverrunMs),
    encoders = RobotState.Encoders(left = r.encoderLeft, right = r.encoderRight),
    wheels = RobotState.Wheels(
        speedLeftMmps = r.speedLeftMmps, speedRightMmps = r.speedRightMmps, pwmLeft = wheels.pwmLeft, pwmRight = wheels.pwmRight,
    ),
    line = RobotState.Line(raw = line.raw, position = r.linePosition, flags = LineFlag.of(r.lineFlags)),
    lineFollow = lineFollow, proximity = proximity, colour = colour, accel = accel, power = power,
    indicators = indicators, locomotion = locomotion, track = track, errors = errors,
)
