package org.pocketbot.sdk.transport

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.catch
import kotlinx.coroutines.flow.channelFlow
import kotlinx.coroutines.launch

/**
 * One search over several [Discoverer]s at once (the embedded emulator, an emulator's control port, Bluetooth, serial
 * ports): robots are emitted as each source finds them, and the search completes when every source is done. A source
 * that fails (no Bluetooth adapter, no emulator running) does not end the others: it is reported to [onFailure] with
 * its name, for a face to show.
 *
 * ```
 * val all = MergedDiscoverer(mapOf("emulator" to EmulatorDiscoverer(), "Bluetooth" to BluezDiscoverer()))
 * all.discover().collect { println(it.name) }
 * ```
 */
public class MergedDiscoverer(
    /** The sources by a name people understand. */
    public val sources: Map<String, Discoverer>,
    private val onFailure: (source: String, error: Throwable) -> Unit = { _, _ -> },
) : Discoverer {
    override fun discover(): Flow<RobotDevice> = channelFlow {
        for ((name, source) in sources) {
            launch {
                source.discover()
                    .catch { e -> if (e is CancellationException) throw e else onFailure(name, e) }
                    .collect { send(it) }
            }
        }
    }
}
