package org.pocketbot.sdk

import org.pocketbot.protocol.Hello

/**
 * Who a robot is, from its `hello` packet.
 *
 * @property robotId settings.identity.robot_id, 1..254; also the id other robots see in IR messages. Not unique
 *   across robots unless someone made it so: every robot starts with id 1.
 * @property name the user-friendly name, e.g. `PocketBot`.
 * @property firmwareVersion `major.minor.patch`.
 * @property protocolVersion the protocol version the firmware speaks.
 * @property layoutHash hash of every packet, settings and state layout of the firmware.
 * @property address where the robot was reached ([org.pocketbot.sdk.transport.Transport.address]).
 */
public class RobotIdentity internal constructor(
    public val robotId: Int,
    public val name: String,
    public val firmwareVersion: String,
    public val protocolVersion: Int,
    public val layoutHash: Long,
    public val address: String,
) {
    override fun equals(other: Any?): Boolean = other is RobotIdentity && robotId == other.robotId && name == other.name &&
        firmwareVersion == other.firmwareVersion && protocolVersion == other.protocolVersion &&
        layoutHash == other.layoutHash && address == other.address

    override fun hashCode(): Int = listOf(robotId, name, firmwareVersion, protocolVersion, layoutHash, address).hashCode()

    override fun toString(): String =
        "$name (id $robotId, firmware $firmwareVersion, protocol v$protocolVersion, layout 0x${layoutHash.toString(16).uppercase()}) at $address"

    internal companion object {
        fun of(hello: Hello, address: String): RobotIdentity = RobotIdentity(
            hello.robotId, hello.name, "${hello.fwMajor}.${hello.fwMinor}.${hello.fwPatch}",
            hello.protocolVersion, hello.layoutHash, address,
        )
    }
}
