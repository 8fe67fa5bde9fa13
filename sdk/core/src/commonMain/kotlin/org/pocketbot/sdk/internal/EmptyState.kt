package org.pocketbot.sdk.internal

import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.StateEncoders
import org.pocketbot.protocol.StateLine
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.StateTime
import org.pocketbot.protocol.StateWheels

/** The state before the first state packet: all zero, robot time 0. */
internal val EMPTY_STATE: RobotState = RobotState.decode(ByteArray(ProtocolInfo.STATE_SIZE), 0)

/** [this] state with the parts a reduced packet carries replaced; everything else stays as last seen. */
internal fun RobotState.merge(r: StateReduced): RobotState = RobotState(
    time = StateTime(timeMs = r.timeMs, tickMaxUs = time.tickMaxUs, overruns = time.overruns, lastOverrunMs = time.lastOverrunMs),
    encoders = StateEncoders(left = r.encoderLeft, right = r.encoderRight),
    wheels = StateWheels(
        speedLeftMmps = r.speedLeftMmps, speedRightMmps = r.speedRightMmps, pwmLeft = wheels.pwmLeft, pwmRight = wheels.pwmRight,
    ),
    line = StateLine(raw = line.raw, position = r.linePosition, flags = r.lineFlags),
    lineFollow = lineFollow, proximity = proximity, colour = colour, accel = accel, power = power,
    indicators = indicators, locomotion = locomotion, track = track, errors = errors,
)
