package org.pocketbot.sdk.mqtt

import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport

/**
 * A robot a gateway serves through the broker: [open] starts a session, a link of its own to the robot through the
 * gateway, which [org.pocketbot.sdk.connect] drives as any other. Made by a [BrokerClient].
 *
 * @property gateway the gateway's name.
 * @property robot the robot's id at that gateway.
 */
public class BrokerRobotDevice internal constructor(
    public val gateway: String,
    public val robot: String,
) : RobotDevice {
    /** The robot's advertised name (from the gateway's announcement), or `<gateway>/<robot>` before it is known. */
    override val name: String get() = TODO()

    /** `mqtt://<broker host:port>/<gateway>/<robot>`. */
    override val address: String get() = TODO()

    /**
     * Opens a session through the gateway. Throws [org.pocketbot.sdk.transport.TransportLostException] saying why
     * when it cannot: the broker is not connected, the gateway is offline, it serves no such robot, or the robot has
     * no free link.
     */
    override suspend fun open(): Transport = TODO()
}
