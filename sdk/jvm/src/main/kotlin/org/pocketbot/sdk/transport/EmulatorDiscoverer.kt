package org.pocketbot.sdk.transport

import java.io.IOException
import java.net.InetSocketAddress
import java.net.Socket
import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.flow
import kotlinx.coroutines.runInterruptible

/**
 * Finds the robots of an emulator running as its own process (`make emulator`, or the emulator's `main`) through
 * its control port: a TCP port on which the emulator answers every connection with one line per robot,
 * `<id>\t<name>\t<tcp port>\t<host>\n` (ASCII; older emulators leave `host` out), then closes it (see
 * emulator/README.md). Each robot becomes a [TcpRobotDevice] at [host] and its port: the host this discoverer reached
 * the control port at, where the robots listen too. The line's `host` (the address the emulator saw the connection
 * arrive at) is not used, because behind port forwarding (an Android emulator's `10.0.2.2`, `adb reverse`) it is not
 * an address the client can reach.
 *
 * [discover] asks once and completes; it throws [TransportLostException] when no emulator answers at
 * [host]:[controlPort] within [timeout]. Robots without a TCP endpoint (port `-1`) and lines it cannot read are
 * left out.
 *
 * ```
 * val robot = EmulatorDiscoverer().discover().first().open()
 * ```
 */
public class EmulatorDiscoverer(
    public val host: String = "127.0.0.1",
    public val controlPort: Int = DEFAULT_CONTROL_PORT,
    public val timeout: Duration = 5.seconds,
) : Discoverer {
    init {
        require(controlPort in 1..65535) { "port $controlPort is not a TCP port" }
    }

    override fun discover(): Flow<RobotDevice> = flow {
        for (device in list()) emit(device)
    }

    /** The robots the emulator lists now, in its order. Suspends while asking; safe from any coroutine. */
    public suspend fun list(): List<TcpRobotDevice> {
        val text = runInterruptible(Dispatchers.IO) {
            try {
                Socket().use { socket ->
                    val millis = timeout.inWholeMilliseconds.coerceIn(1, Int.MAX_VALUE.toLong()).toInt()
                    socket.connect(InetSocketAddress(host, controlPort), millis)
                    socket.soTimeout = millis
                    socket.getInputStream().readBytes().toString(Charsets.US_ASCII)
                }
            } catch (e: IOException) {
                throw TransportLostException(
                    "no emulator control port at $host:$controlPort: ${e.message ?: e::class.simpleName}", e)
            }
        }
        return parse(text)
    }

    internal fun parse(text: String): List<TcpRobotDevice> = text.lineSequence().mapNotNull { line ->
        val parts = line.trimEnd('\r').split('\t')
        if (parts.size < 3) return@mapNotNull null
        val port = parts[2].trim().toIntOrNull()?.takeIf { it in 1..65535 } ?: return@mapNotNull null
        parts[0].trim().toIntOrNull() ?: return@mapNotNull null
        TcpRobotDevice(host, port, name = parts[1])
    }.toList()

    override fun toString(): String = "EmulatorDiscoverer($host:$controlPort)"

    public companion object {
        /** The control port an emulator started from the command line listens on unless told otherwise. */
        public const val DEFAULT_CONTROL_PORT: Int = 40000
    }
}
