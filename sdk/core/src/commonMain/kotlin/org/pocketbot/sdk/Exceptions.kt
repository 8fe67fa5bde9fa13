package org.pocketbot.sdk

import org.pocketbot.protocol.PACKET_SPECS
import org.pocketbot.sdk.transport.RobotDevice

/** Base of every error the SDK throws about a robot. */
public open class RobotException(message: String, cause: Throwable? = null) : Exception(message, cause)

/**
 * The robot's firmware and this SDK do not speak the same protocol; the message names both versions.
 * Update the firmware or the SDK so that both are generated from the same `protocol/pocketbot.toml`.
 */
public class ProtocolMismatchException internal constructor(
    /** Protocol version the robot announced. */
    public val robotVersion: Int,
    /** Layout hash the robot announced. */
    public val robotLayoutHash: Long,
    /** Protocol version of this SDK. */
    public val sdkVersion: Int,
    /** Layout hash of this SDK. */
    public val sdkLayoutHash: Long,
) : RobotException(
    "protocol mismatch: robot speaks protocol v$robotVersion (layout 0x${robotLayoutHash.toString(16).uppercase()}), " +
        "this SDK speaks protocol v$sdkVersion (layout 0x${sdkLayoutHash.toString(16).uppercase()})",
)

/**
 * The robot answered a command with an `error` packet: it was refused and not executed.
 *
 * @property command the refused command's name in the protocol, e.g. `move_straight`.
 * @property code what the robot objected to.
 * @property detail code-specific (docs/protocol.md): the offending settings offset, the byte offset of the bad
 *   argument in the command, the length.
 */
public open class CommandRefusedException internal constructor(
    public val command: String,
    public val code: ErrorCode,
    public val detail: Int,
    message: String = "robot refused ${command.replace('_', ' ')}: ${describe(code, detail)}",
) : RobotException(message) {
    internal constructor(packetType: Int, rawCode: Int, detail: Int) :
        this(commandName(packetType), errorCodeOf(rawCode), detail)
}

/**
 * A command that changes the robot, on a robot this host does not drive: another host drives it ([driver], its label,
 * when known) or none does. Thrown at once, without sending, when this host knows it watches; also when the robot
 * refuses the command because the drive changed meanwhile. Take the drive with [Robot.takeOver] (or ask for it with
 * [Robot.setRole]); [Robot.driving] says who drives.
 */
public class NotDriverException internal constructor(
    /** The robot's name. */
    public val robot: String,
    command: String,
    /** The label of the host that drives the robot, or null when no host drives it (or this host does not know). */
    public val driver: String?,
) : CommandRefusedException(
    command, ErrorCode.NOT_DRIVER, 0,
    if (driver != null) "$robot is driven by $driver" else "$robot is not driven by this host",
)

/** The robot refused to write the setting [name] to [value]: outside its min..max, or not a whole field. */
public class SettingRefusedException internal constructor(
    /** The setting's name, e.g. `line_pid.kp`. */
    public val name: String,
    /** The value that was refused. */
    public val value: Any?,
    code: ErrorCode,
    detail: Int,
    /** [value] as people read it ([SettingField.format]). */
    valueText: String = value.toString(),
    /** What the robot accepts, as people read it ([SettingField.rangeText]); empty when unbounded. */
    range: String = "",
) : CommandRefusedException(
    "update_settings", code, detail,
    "robot refused $name = $valueText: " +
        if (code == ErrorCode.SETTINGS_VALUE) "outside the range it accepts" + (if (range.isEmpty()) "" else " ($range)") else describe(code, detail),
)

/** A command was sent [attempts] times on a live link and never acknowledged. */
public class CommandTimeoutException internal constructor(
    /** The command's name in the protocol. */
    public val command: String,
    /** How often it was sent. */
    public val attempts: Int,
) : RobotException("$command not acknowledged after $attempts attempts") {
    internal constructor(packetType: Int, attempts: Int) : this(commandName(packetType), attempts)
}

/**
 * Too many acknowledged commands of one robot wait for an answer at once ([window] of them): the newest is refused
 * rather than queued without end. It happens only when the robot stops answering while commands keep coming; each
 * waiting command ends by itself with its timeout.
 */
public class CommandWindowFullException internal constructor(
    /** How many commands may wait for an answer at a time. */
    public val window: Int,
) : RobotException("$window commands already wait for the robot's answer; refusing another until some are answered")

/** The robot was closed (by [Robot.close], or after the SDK gave up reconnecting) before the operation finished. */
public class RobotClosedException internal constructor(message: String, cause: Throwable? = null) : RobotException(message, cause)

/** The first link to a robot could not be established (no answer to `hello_request`, transport failed). */
public class ConnectFailedException internal constructor(message: String, cause: Throwable? = null) : RobotException(message, cause)

/**
 * Fewer robots than asked for turned up within [timeout]: [found] lists those that did (none of them was connected).
 */
public class RobotsNotFoundException internal constructor(
    /** How many robots were asked for. */
    public val wanted: Int,
    /** The devices found, in the order they turned up. */
    public val found: List<RobotDevice>,
    timeout: kotlin.time.Duration,
) : RobotException(
    "found ${found.size} of $wanted robots within $timeout" +
        if (found.isEmpty()) "" else ": " + found.joinToString { if (it.name == it.address) it.address else "${it.name} at ${it.address}" },
)

internal fun commandName(packetType: Int): String = PACKET_SPECS[packetType]?.name ?: "packet 0x${packetType.toString(16)}"

internal fun errorCodeOf(raw: Int): ErrorCode = ErrorCode.fromCode(raw)

/** What the robot objected to, in words (the protocol's names of [ErrorCode] are for programs). */
internal fun describe(code: ErrorCode, detail: Int): String = when (code) {
    ErrorCode.SETTINGS_RANGE -> "not a whole setting (offset $detail)"
    ErrorCode.SETTINGS_VALUE -> "a value outside the range it accepts"
    ErrorCode.QUEUE_FULL -> "its movement queue is full"
    ErrorCode.BAD_ARGUMENT -> "an argument it does not accept (at byte $detail of the command)"
    ErrorCode.BUSY -> "it is busy with something that cannot wait"
    ErrorCode.BAD_SEQUENCE -> "a command out of sequence"
    ErrorCode.BAD_LENGTH, ErrorCode.TOO_SHORT, ErrorCode.TOO_LONG -> "a command of the wrong length"
    ErrorCode.BAD_CRC, ErrorCode.FRAMING -> "a damaged frame"
    ErrorCode.UNKNOWN_TYPE -> "a command it does not know"
    else -> "error code ${code.code} (detail $detail)"
}
