package org.pocketbot.sdk.transport

import com.fazecast.jSerialComm.SerialPort
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.channelFlow
import kotlinx.coroutines.launch
import kotlinx.coroutines.withContext
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.ProtocolInfo
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * Finds robots on serial ports: RFCOMM ttys bound to PocketBots, USB serial adapters, ptys. A serial port cannot
 * say what is behind it, so each candidate port is asked with a `hello_request` and becomes a [SerialRobotDevice]
 * named after the robot only if a robot answers within [answerTimeout]. Ports are probed in parallel; a busy or
 * unopenable port is skipped. [discover] completes when every port answered or timed out.
 *
 * @param ports the ports to try; by default the system's ports that can carry a robot (`/dev/rfcomm*`, `/dev/ttyUSB*`,
 *   `/dev/ttyACM*`, `COM*`, macOS `cu.*`), not the motherboard's `/dev/ttyS*` (probing those writes to whatever is
 *   wired there).
 */
public class SerialDiscoverer(
    private val ports: () -> List<String> = ::candidatePorts,
    public val baud: Int = SerialTransport.DEFAULT_BAUD,
    public val answerTimeout: Duration = 500.milliseconds,
) : Discoverer {
    override fun discover(): Flow<RobotDevice> = channelFlow {
        for (path in withContext(Dispatchers.IO) { ports() }) {
            launch {
                probe(path)?.let { send(it) }
            }
        }
    }

    /** The robot behind [path], or null when nothing answered like a PocketBot. */
    public suspend fun probe(path: String): SerialRobotDevice? {
        val transport = try {
            SerialTransport.open(path, baud)
        } catch (e: TransportLostException) {
            return null
        }
        try {
            // Session 0: asking who is there starts no session of ours on the robot.
            transport.send(Frames.encode(HelloRequest(ProtocolInfo.VERSION, 0L), 0))
            val hello = withTimeoutOrNull(answerTimeout) {
                for (frame in transport.incoming) {
                    val r = Frames.decode(frame)
                    if (r is FrameResult.Decoded && r.packet is Hello) return@withTimeoutOrNull r.packet as Hello
                }
                null
            } ?: return null
            return SerialRobotDevice(path, baud, hello.name.ifBlank { path })
        } catch (e: TransportLostException) {
            return null
        } finally {
            transport.close()
        }
    }

    public companion object {
        private val CANDIDATE = Regex("""(rfcomm\d+|ttyUSB\d+|ttyACM\d+|COM\d+|cu\..+)$""")

        /** The system's serial ports that can carry a robot, by path. */
        public fun candidatePorts(): List<String> = SerialPort.getCommPorts()
            .map { it.systemPortPath }
            .filter { CANDIDATE.containsMatchIn(it) }
            .sorted()
    }
}
