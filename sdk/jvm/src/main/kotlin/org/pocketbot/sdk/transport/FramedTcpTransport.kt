package org.pocketbot.sdk.transport

import kotlinx.coroutines.Dispatchers
import org.pocketbot.sdk.transport.internal.SocketLoop
import kotlin.coroutines.CoroutineContext
import kotlin.time.Duration

/**
 * A [Transport] over TCP that carries frames whole, each after a 2-byte little-endian length (see
 * [LengthPrefixedStreamTransport]): how the Bluetooth gateway (emulator/bluetooth) offers a robot's framed L2CAP
 * channel, one frame per L2CAP SDU. Sockets, event loops and `TCP_NODELAY` are [TcpTransport]'s; framing errors,
 * a lost link and [close] are [ByteStreamTransport]'s behaviour. Safe to use from any thread and coroutine.
 *
 * ```
 * val transport = FramedTcpTransport.open("127.0.0.1", l2capPort)
 * transport.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, session), seq = 1))
 * println(Frames.decode(transport.incoming.receive()))
 * transport.close()
 * ```
 */
public class FramedTcpTransport private constructor(
    address: String,
    stream: ByteStream,
    context: CoroutineContext,
) : LengthPrefixedStreamTransport(address, stream, context) {
    public companion object {
        /**
         * Connects to [host]:[port] and returns the open transport; suspends until connected. Throws
         * [TransportLostException] when nothing accepts the connection within [timeout].
         *
         * @param context where the transport's reader runs; its [kotlinx.coroutines.Job], if any, becomes the
         *   parent of the reader.
         */
        public suspend fun open(
            host: String,
            port: Int,
            timeout: Duration = TcpTransport.DEFAULT_CONNECT_TIMEOUT,
            context: CoroutineContext = Dispatchers.Unconfined,
        ): FramedTcpTransport = connect(host, port, timeout, context, SocketLoop.next())

        /** The old name of [open]. */
        @Deprecated("open, the verb SerialTransport.open and RobotDevice.open use", ReplaceWith("open(host, port, timeout, context)"))
        public suspend fun connect(
            host: String,
            port: Int,
            timeout: Duration = TcpTransport.DEFAULT_CONNECT_TIMEOUT,
            context: CoroutineContext = Dispatchers.Unconfined,
        ): FramedTcpTransport = open(host, port, timeout, context)

        /** [open] with its socket served by [loop]. */
        internal suspend fun connect(
            host: String,
            port: Int,
            timeout: Duration,
            context: CoroutineContext = Dispatchers.Unconfined,
            loop: SocketLoop,
        ): FramedTcpTransport =
            FramedTcpTransport(TcpTransport.tcpAddress(host, port), TcpTransport.openSocket(host, port, timeout, loop), context)
    }
}
