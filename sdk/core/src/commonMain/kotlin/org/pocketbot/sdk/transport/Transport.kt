package org.pocketbot.sdk.transport

import kotlinx.coroutines.channels.ReceiveChannel
import kotlinx.coroutines.flow.Flow

/**
 * A link to one robot that carries whole frames: the 3-byte header, the payload and the CRC, without SLIP.
 *
 * One implementation per way of reaching a robot (TCP, serial, Bluetooth, the emulator in-process); stream
 * links do their own SLIP framing. A transport is open when it is handed out and stays open until [close]
 * or until the link is lost.
 */
public interface Transport {
    /** Where the robot is, for people and logs: `tcp://127.0.0.1:40001`, `serial:/dev/rfcomm0`, `emulator:3`. */
    public val address: String

    /**
     * Frames from the robot, in arrival order. Closed normally after [close]; closed with a
     * [TransportLostException] when the link breaks.
     */
    public val incoming: ReceiveChannel<ByteArray>

    /** Sends one frame. Throws [TransportLostException] when the link is gone. Safe to call from any coroutine. */
    public suspend fun send(frame: ByteArray)

    /** Closes the link; idempotent. */
    public fun close()
}

/** The link to a robot broke (socket closed, device gone, no answer). */
public class TransportLostException(message: String, cause: Throwable? = null) : Exception(message, cause)

/** A robot that can be connected: what a [Discoverer] finds. */
public interface RobotDevice {
    /** The robot's advertised name, e.g. `PocketBot-3`. */
    public val name: String

    /** Where the robot is (see [Transport.address]). */
    public val address: String

    /** Opens a new link to the robot. Throws [TransportLostException] when the robot cannot be reached. */
    public suspend fun open(): Transport
}

/** Finds connectible robots. */
public interface Discoverer {
    /** Emits each robot found; completes when the search is over. */
    public fun discover(): Flow<RobotDevice>
}
