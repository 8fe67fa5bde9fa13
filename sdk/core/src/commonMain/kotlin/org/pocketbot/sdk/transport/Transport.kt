package org.pocketbot.sdk.transport

import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.channels.ReceiveChannel
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow

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

    /**
     * Frames this transport dropped before they became frames (a stream link's broken SLIP, a frame longer than
     * the protocol allows), counted since it opened. [org.pocketbot.sdk.Robot.linkStats] adds them up. Transports
     * that cannot lose frames that way keep the default, which stays at zero.
     */
    public val droppedFrames: StateFlow<DroppedFrames> get() = NO_DROPS

    /** Closes the link; idempotent. */
    public fun close()
}

/**
 * Frames a transport dropped before delivering them.
 *
 * @property tooLong frames longer than the protocol's largest frame.
 * @property badFraming frames whose framing was broken (an invalid SLIP escape).
 */
public class DroppedFrames(public val tooLong: Long = 0, public val badFraming: Long = 0) {
    /** Every dropped frame. */
    public val total: Long get() = tooLong + badFraming

    override fun equals(other: Any?): Boolean = other is DroppedFrames && tooLong == other.tooLong && badFraming == other.badFraming
    override fun hashCode(): Int = tooLong.hashCode() * 31 + badFraming.hashCode()
    override fun toString(): String = "DroppedFrames(tooLong=$tooLong, badFraming=$badFraming)"
}

private val NO_DROPS: StateFlow<DroppedFrames> = MutableStateFlow(DroppedFrames()).asStateFlow()

/** The link to a robot broke (socket closed, device gone, no answer). */
public class TransportLostException(message: String, cause: Throwable? = null) : Exception(message, cause)

/** A robot that can be connected: what a [Discoverer] finds. */
public interface RobotDevice {
    /** The robot's advertised name, e.g. `PocketBot-3`. */
    public val name: String

    /** Where the robot is (see [Transport.address]). */
    public val address: String

    /**
     * How fast the link to the robot carries bytes. Every PocketBot2 link is its 115200 Bd UART or carries it (the
     * Bluetooth SPP module, a serial-to-TCP bridge, the emulator's TCP endpoint); a device that knows better says so.
     */
    public val linkRate: LinkRate get() = LinkRate.SERIAL_115200

    /**
     * The one thread that runs this device's I/O, as a dispatcher, or null when it has none. When there is one, the
     * SDK runs the robot's link on it too, so a frame goes from the socket to [org.pocketbot.sdk.Robot.state] on one
     * thread, with no hand-over (the JVM's TCP devices share one such event loop). Code that collects the robot's
     * flows in `Dispatchers.Unconfined` then runs on that thread as well, and must not block it.
     */
    public val eventLoop: CoroutineDispatcher? get() = null

    /** Opens a new link to the robot. Throws [TransportLostException] when the robot cannot be reached. */
    public suspend fun open(): Transport
}

/** Finds connectible robots. */
public interface Discoverer {
    /** Emits each robot found; completes when the search is over. */
    public fun discover(): Flow<RobotDevice>
}
