package org.pocketbot.sdk.transport

import com.fazecast.jSerialComm.SerialPort
import java.io.IOException
import kotlin.coroutines.CoroutineContext
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.ensureActive
import kotlinx.coroutines.runInterruptible
import kotlinx.coroutines.withContext

/**
 * A [Transport] over a serial port with SLIP framing, through jSerialComm: a Bluetooth RFCOMM tty bound with
 * `rfcomm bind` (`/dev/rfcomm0`, the robot's SPP link), a USB serial adapter wired to the robot's UART
 * (`/dev/ttyUSB0`, `COM3`), or a pseudo-terminal (`/dev/pts/N`, or a symlink to one as `socat` makes them).
 *
 * The port is opened 8N1 without flow control at the given baud rate (which an RFCOMM tty ignores). Reads wait
 * in [Dispatchers.IO] threads, waking every [POLL_INTERVAL_MS] ms to notice [close]; when the device goes away
 * (the Bluetooth link dropped, the adapter was unplugged, the pty's other end closed) reads fail and the link is
 * lost, as [SlipStreamTransport] describes. Safe to use from any thread and coroutine.
 *
 * ```
 * val transport = SerialTransport.open("/dev/rfcomm0")
 * ```
 */
public class SerialTransport private constructor(
    address: String,
    stream: ByteStream,
    context: CoroutineContext,
) : SlipStreamTransport(address, stream, context) {
    public companion object {
        /** The PocketBot2's UART speed, in bit/s. */
        public const val DEFAULT_BAUD: Int = 115_200

        /** How often a waiting read wakes up to check whether the transport was closed, in milliseconds. */
        public const val POLL_INTERVAL_MS: Int = 100

        /**
         * Opens the serial port at [path] (`/dev/rfcomm0`, `/dev/ttyUSB0`, `COM3`, a pty) at [baud] bit/s, 8N1,
         * and returns the open transport. Throws [TransportLostException] when the port cannot be opened (it does
         * not exist, is busy, or permission is missing: on Linux, join the `dialout` group).
         *
         * @param context where the transport's reader runs; its [kotlinx.coroutines.Job], if any, becomes the
         *   parent of the reader.
         */
        public suspend fun open(
            path: String,
            baud: Int = DEFAULT_BAUD,
            context: CoroutineContext = Dispatchers.IO,
        ): SerialTransport {
            require(baud > 0) { "baud rate must be positive, was $baud" }
            val address = serialAddress(path)
            val port = runInterruptible(Dispatchers.IO) {
                val port = try {
                    SerialPort.getCommPort(path)
                } catch (e: Exception) {
                    throw TransportLostException("$address: no such serial port (${e.message})", e)
                }
                port.setComPortParameters(baud, 8, SerialPort.ONE_STOP_BIT, SerialPort.NO_PARITY)
                port.setFlowControl(SerialPort.FLOW_CONTROL_DISABLED)
                port.setComPortTimeouts(
                    SerialPort.TIMEOUT_READ_SEMI_BLOCKING or SerialPort.TIMEOUT_WRITE_BLOCKING, POLL_INTERVAL_MS, 0)
                if (!port.openPort()) {
                    throw TransportLostException(
                        "$address: cannot open the serial port (error ${port.lastErrorCode}); " +
                            "does it exist, is it free, may this user open it?")
                }
                port
            }
            return SerialTransport(address, PortStream(port, path), context)
        }

        internal fun serialAddress(path: String): String = "serial:$path"
    }
}

/** A jSerialComm port as a [ByteStream]. */
private class PortStream(private val port: SerialPort, private val path: String) : ByteStream {
    @Volatile private var closed = false

    override suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int = withContext(Dispatchers.IO) {
        var n = 0
        while (n == 0) {
            if (closed) return@withContext -1
            n = port.readBytes(buffer, length, offset)
            if (n == 0) ensureActive()
        }
        when {
            n > 0 -> n
            closed -> -1
            else -> throw IOException("$path: the device is gone (read failed, error ${port.lastErrorCode})")
        }
    }

    override suspend fun write(bytes: ByteArray) = withContext(Dispatchers.IO) {
        var done = 0
        while (done < bytes.size) {
            if (closed) throw IOException("$path: the port is closed")
            val n = port.writeBytes(bytes, bytes.size - done, done)
            if (n <= 0) throw IOException("$path: the device is gone (write failed, error ${port.lastErrorCode})")
            done += n
        }
    }

    override fun close() {
        if (closed) return
        closed = true
        port.closePort()
    }
}
