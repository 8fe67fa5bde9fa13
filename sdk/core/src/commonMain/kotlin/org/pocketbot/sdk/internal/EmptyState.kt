package org.pocketbot.sdk.internal

import org.pocketbot.protocol.ProximitySide
import org.pocketbot.protocol.RobotState
import org.pocketbot.protocol.StateAccel
import org.pocketbot.protocol.StateColour
import org.pocketbot.protocol.StateEncoders
import org.pocketbot.protocol.StateErrors
import org.pocketbot.protocol.StateIndicators
import org.pocketbot.protocol.StateLine
import org.pocketbot.protocol.StateLineFollow
import org.pocketbot.protocol.StateLocomotion
import org.pocketbot.protocol.StatePower
import org.pocketbot.protocol.StateProximity
import org.pocketbot.protocol.StateReduced
import org.pocketbot.protocol.StateTime
import org.pocketbot.protocol.StateWheels

/** The state before the first state packet: all zero, robot time 0. */
internal val EMPTY_STATE: RobotState = RobotState(
    StateTime(0, 0, 0), StateEncoders(0, 0), StateWheels(0, 0, 0, 0), StateLine(List(8) { 0 }, 0, 0),
    StateLineFollow(0, 0), StateProximity(ProximitySide(0, 0, 0, 0), ProximitySide(0, 0, 0, 0)),
    StateColour(0, 0, 0, 0, 0), StateAccel(0, 0, 0), StatePower(0, 0, 0), StateIndicators(0, 0),
    StateLocomotion(0, 0, 0, 0), StateErrors(0, 0, 0, 0, 0),
)

/** [this] state with the parts a reduced packet carries replaced; everything else stays as last seen. */
internal fun RobotState.merge(r: StateReduced): RobotState = copy(
    time = time.copy(timeMs = r.timeMs),
    encoders = StateEncoders(r.encoderLeft, r.encoderRight),
    wheels = wheels.copy(speedLeftMmps = r.speedLeftMmps, speedRightMmps = r.speedRightMmps),
    line = line.copy(position = r.linePosition, flags = r.lineFlags),
)
