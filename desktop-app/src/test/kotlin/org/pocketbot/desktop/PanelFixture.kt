package org.pocketbot.desktop

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import org.pocketbot.desktop.model.EmulatorModel
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.protocol.FieldType
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.HostLabel
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.transport.Discoverer
import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.ByteOrder

/**
 * A panel as `make run` builds it, on an embedded emulator running the real firmware in real time, with the SDK's
 * default options (a private settings cache, so tests do not share one) and no other discoverers.
 */
class PanelFixture(
    world: String = "round",
    robots: Int = 1,
    sources: Map<String, Discoverer> = emptyMap(),
    /** Where the emulator is served on the network when asked to (any free port, so tests do not collide). */
    serveAt: InetSocketAddress = InetSocketAddress(ListenAddress.ANY, 0),
) : AutoCloseable {
    val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    val emulator = EmulatorModel(scope, world, robots, serveAt = serveAt)
    val panel = PanelModel(scope, sources, emulator, RobotOptions { settingsCache = InMemorySettingsCache(); hostLabel = HostLabel.of("panel") })

    /** The float setting [name] as the emulated robot [id] holds it in its own settings bytes. */
    fun robotFloat(name: String, id: Int = 1): Float {
        check(SETTINGS_FIELDS.single { it.path == name }.type == FieldType.F32) { "$name is no float" }
        val field = SETTINGS_FIELDS.single { it.path == name }
        val bytes = emulator.handleFor("emulator:$id")!!.settingsBytes()
        return ByteBuffer.wrap(bytes).order(ByteOrder.LITTLE_ENDIAN).getFloat(field.offset)
    }

    override fun close() {
        panel.close()
        scope.cancel()
    }
}

/** The emulated robot [id]'s debug level, as it holds it. */
fun PanelFixture.robotDebugLevel(id: Int = 1): Int =
    emulator.handleFor("emulator:$id")!!.settingsBytes()[SETTINGS_FIELDS.single { it.path == "debug.level" }.offset].toInt()
