package org.pocketbot.emulator.transport

import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.flow
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.link.LinkConnection
import org.pocketbot.emulator.link.RobotLink
import org.pocketbot.emulator.link.RobotLinks
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.LinkRate
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException
import kotlin.time.Duration.Companion.seconds

/**
 * A [Transport] to a robot of an emulator running in this JVM: frames are SLIP-encoded into a simulated serial link
 * of the robot's own (baud rate, latency, faults) and decoded out of it, exactly as over TCP or Bluetooth, without
 * sockets. Each transport is a host of its own on the robot, on a link of its own; with every link in use it is
 * refused ([TransportLostException] from the constructor).
 */
internal class InProcessTransport(
    links: RobotLinks,
    override val address: String,
) : Transport, LinkConnection {
    private val frames = Channel<ByteArray>(Channel.UNLIMITED)
    private val decoder = SlipDecoder()
    @Volatile private var closed = false
    private val link: RobotLink = try {
        links.attach(this)
    } catch (e: IllegalStateException) { // the link is down, or every link carries a host
        throw TransportLostException("$address: ${e.message}", e)
    }

    /** SLIP frames the decoder dropped (corrupted framing) on the way from the robot. */
    @Volatile public var framingErrors: Int = 0
        private set

    override val incoming: ReceiveChannel<ByteArray> get() = frames

    override suspend fun send(frame: ByteArray) {
        if (closed) throw TransportLostException("$address: transport is closed")
        link.hostSend(Slip.encode(frame))
    }

    override fun close() {
        if (closed) return
        closed = true
        link.detach(this)
        frames.close()
    }

    // Called on the emulator's stepping thread.
    override fun onBytes(bytes: ByteArray) {
        if (closed) return
        synchronized(decoder) {
            decoder.feed(bytes, onError = { framingErrors++ }) { frames.trySend(it) }
        }
    }

    override fun onLinkLost(reason: String) {
        if (closed) return
        closed = true
        link.detach(this)
        frames.close(TransportLostException("$address: $reason"))
    }
}

/**
 * A robot of an embedded emulator, as a [Discoverer] finds it. [open] first makes sure that something steps the
 * emulator (its own thread, a simulated run): without, the robot could never answer, and the connect would fail
 * seconds later with a handshake timeout that does not say why.
 */
internal class InProcessDevice(
    override val name: String,
    override val address: String,
    private val links: RobotLinks,
    private val emulator: Emulator,
) : RobotDevice {
    override suspend fun open(): Transport {
        if (!emulator.isStepped(NOT_STEPPED_AFTER)) throw TransportLostException(
            "$address: the emulator is not running, so its robots cannot answer: call emulator.start() to run it in " +
                "real time, or connect inside emulator.runSimulated { } to run it on simulated time",
        )
        return InProcessTransport(links, address)
    }

    /** The simulated link's baud rate as it is set now ([org.pocketbot.emulator.RobotHandle.link]). */
    override val linkRate: LinkRate get() = LinkRate.ofBaud(links.settings.baud)

    override fun toString(): String = "$name ($address)"

    private companion object {
        /** Far longer than a step takes, however loaded the machine; simulated time in a simulated run. */
        val NOT_STEPPED_AFTER = 2.seconds
    }
}

/** Finds the robots of an embedded emulator: each robot present when [discover] is collected. */
internal class InProcessDiscoverer(private val devices: () -> List<RobotDevice>) : Discoverer {
    override fun discover(): Flow<RobotDevice> = flow { for (d in devices()) emit(d) }
}
