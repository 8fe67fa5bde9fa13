package org.pocketbot.sdk

import org.pocketbot.protocol.ErrorCode
import org.pocketbot.protocol.PACKET_SPECS

/** Base of every error the SDK throws about a robot. */
public open class RobotException(message: String, cause: Throwable? = null) : Exception(message, cause)

/**
 * The robot's firmware and this SDK do not speak the same protocol; the message names both versions.
 * Update the firmware or the SDK so that both are generated from the same `protocol/pocketbot.toml`.
 */
public class ProtocolMismatchException(
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
 * @property packetType the refused packet's type (see [PACKET_SPECS]).
 * @property code what the robot objected to, or null for a code this SDK does not know ([rawCode]).
 * @property detail code-specific: the offending offset, length or value.
 */
public open class CommandRefusedException(
    public val packetType: Int,
    public val rawCode: Int,
    public val detail: Int,
    message: String = "robot refused ${PACKET_SPECS[packetType]?.name ?: "packet 0x${packetType.toString(16)}"}: " +
        "${ErrorCode.fromCode(rawCode)?.name ?: "error $rawCode"} (detail $detail)",
) : RobotException(message) {
    public val code: ErrorCode? get() = ErrorCode.fromCode(rawCode)
}

/** The robot refused to write the setting at [path] to [value] (out of its min..max, or not a field boundary). */
public class SettingRefusedException(
    /** Dotted path of the setting, e.g. `line_pid.kp`. */
    public val path: String,
    /** The value that was refused. */
    public val value: Any?,
    packetType: Int,
    rawCode: Int,
    detail: Int,
) : CommandRefusedException(
    packetType, rawCode, detail,
    "robot refused setting $path = $value: ${ErrorCode.fromCode(rawCode)?.name ?: "error $rawCode"} (detail $detail)",
)

/** A command was sent [attempts] times on a live link and never acknowledged. */
public class CommandTimeoutException(
    /** The command's packet type. */
    public val packetType: Int,
    /** How often it was sent. */
    public val attempts: Int,
) : RobotException("${PACKET_SPECS[packetType]?.name ?: "packet 0x${packetType.toString(16)}"} not acknowledged after $attempts attempts")

/** The robot was closed (by [Robot.close], or after the SDK gave up reconnecting) before the operation finished. */
public class RobotClosedException(message: String, cause: Throwable? = null) : RobotException(message, cause)

/** The first link to a robot could not be established (no answer to `hello_request`, transport failed). */
public class ConnectFailedException(message: String, cause: Throwable? = null) : RobotException(message, cause)
