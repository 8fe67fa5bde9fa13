package org.pocketbot.bench

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.delay
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.EmulatorConfig
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.bluetooth.VirtualBluetooth
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.StateUpdate
import org.pocketbot.sdk.SyncMode
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.TcpFraming
import org.pocketbot.sdk.transport.TcpRobotDevice
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds
import kotlin.time.TimeSource

/**
 * `make bench-bluetooth`: full state packets a second that reach the SDK when the robot sends them as fast as its
 * 115200 Bd UART lets it, over the direct link (the UART carries SLIP frames: the serial-module build) and over the
 * robot's own Bluetooth (the UART carries H4 to a virtual controller; the SDK on the gateway's RFCOMM and L2CAP
 * endpoints). Every line is `bluetooth <metric>=<value>`; the shares are taken within this one run.
 *
 *   java -cp sdk/bench/target/classes:$(cat sdk/bench/target/classpath.txt) org.pocketbot.bench.BluetoothBenchKt [seconds]
 */
fun main(args: Array<String>) {
    val seconds = args.firstOrNull()?.toInt() ?: 10
    val uart = Emulator.local(1).use { emu ->
        emu.start(Speed.Realtime(1.0))
        val port = emu.robots[0].startTcp()
        measure("uart", emu, TcpRobotDevice("127.0.0.1", port), seconds)
    }
    // 11 520 bytes a second at 115200 Bd (8N1); a full state frame is 3 + payload + 2 bytes plus two SLIP ENDs.
    val uartWire = 115_200 / 10.0 / (ProtocolInfo.STATE_SIZE + 7)
    line("uart_wire_limit_states_per_s", "%.1f".format(uartWire))
    VirtualBluetooth.start(controllers = 1).use { bt ->
        val bridge = bt.bridge(bt.controllers[0].address)
        for ((kind, at, framing) in listOf(Triple("rfcomm", bridge.rfcomm, TcpFraming.SLIP), Triple("l2cap", bridge.l2cap, TcpFraming.LENGTH_PREFIXED))) {
            Emulator.local(1, config = EmulatorConfig(firmware = FirmwareImage.compiledHci())).use { emu ->
                emu.robots[0].attachH4(bt.controllers[0].h4)
                emu.start(Speed.Realtime(1.0))
                val rate = measure(kind, emu, TcpRobotDevice(at.hostString, at.port, framing = framing), seconds)
                line("${kind}_share_of_uart", "%.1f%%".format(100 * rate / uart))
                line("${kind}_framing_cost", "%.1f%%".format(100 * (1 - rate / uart)))
            }
            bt.reset(1)
        }
    }
}

/**
 * Connects, asks for full state every millisecond (the robot then sends as fast as its UART drains), and counts the
 * full states the SDK receives in about [seconds]; prints them per second of the robot's own clock (the time each
 * state carries: a busy machine may let the emulator lag behind the wall clock and catch up in a burst), and the
 * robot's UART bytes per state.
 */
private fun measure(kind: String, emu: Emulator, device: TcpRobotDevice, seconds: Int): Double = runBlocking(Dispatchers.Default) {
    val sim = emu.robots[0]
    val robot = connectWhenReachable(device)
    robot.reflector.set(SyncMode.FULL, 1.milliseconds)
    delay(1.seconds) // the stream settles
    val times = ArrayList<Long>()
    val bytes0 = sim.linkBytesToHost
    withTimeoutOrNull(seconds.seconds) {
        robot.stateUpdates.collect { if (it.kind == StateUpdate.Kind.FULL) times += it.timeMs }
    }
    val uartBytes = sim.linkBytesToHost - bytes0
    val states = times.size - 1
    val rate = states / ((times.last() - times.first()) / 1000.0)
    line("${kind}_states_per_s", "%.1f".format(rate))
    line("${kind}_uart_bytes_per_state", "%.1f".format(uartBytes.toDouble() / states.coerceAtLeast(1)))
    line("${kind}_dropped_frames", robot.linkStats.value.dropped.toString())
    robot.close()
    rate
}

/** The HCI robot's stack brings its controller up after boot; until then the gateway's page fails. */
private suspend fun CoroutineScope.connectWhenReachable(device: TcpRobotDevice): Robot {
    val deadline = TimeSource.Monotonic.markNow() + 10.seconds
    while (true) {
        try {
            return device.connect(this, RobotOptions { settingsCache = InMemorySettingsCache() })
        } catch (e: Exception) {
            if (deadline.hasPassedNow()) throw IllegalStateException("${device.address} not reachable in 10 s", e)
            delay(100.milliseconds)
        }
    }
}

private fun line(metric: String, value: String) = println("bluetooth $metric=$value")
