package org.pocketbot.sdk

import org.pocketbot.protocol.Hello

/**
 * Who a robot is, from its `hello` packet.
 *
 * @property robotId settings.identity.robot_id, 1..254; also the id other robots see in IR messages.
 * @property name the user-friendly name, e.g. `PocketBot`.
 * @property firmwareVersion `major.minor.patch`.
 * @property protocolVersion the protocol version the firmware speaks.
 * @property layoutHash hash of every packet, settings and state layout of the firmware.
 * @property address where the robot was reached ([org.pocketbot.sdk.transport.Transport.address]).
 */
public data class RobotIdentity(
    public val robotId: Int,
    public val name: String,
    public val firmwareVersion: String,
    public val protocolVersion: Int,
    public val layoutHash: Long,
    public val address: String,
)

internal fun identityOf(hello: Hello, address: String): RobotIdentity = RobotIdentity(
    hello.robotId, hello.name, "${hello.fwMajor}.${hello.fwMinor}.${hello.fwPatch}",
    hello.protocolVersion, hello.layoutHash, address,
)
