package org.pocketbot.bench

import io.ktor.network.selector.SelectorManager
import io.ktor.network.sockets.Socket
import io.ktor.network.sockets.aSocket
import io.ktor.network.sockets.openReadChannel
import io.ktor.network.sockets.openWriteChannel
import io.ktor.utils.io.readAvailable
import io.ktor.utils.io.writeFully
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.channels.ReceiveChannel
import kotlinx.coroutines.delay
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.protocol.Ack
import org.pocketbot.protocol.Crc16
import org.pocketbot.protocol.Driver
import org.pocketbot.protocol.FrameResult
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Hello
import org.pocketbot.protocol.HelloRequest
import org.pocketbot.protocol.MovementLog
import org.pocketbot.protocol.PACKET_SPECS
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.protocol.ReadMovements
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SETTINGS_DEFAULTS
import org.pocketbot.protocol.SetRole
import org.pocketbot.protocol.SetSync
import org.pocketbot.protocol.SettingsData
import org.pocketbot.protocol.Slip
import org.pocketbot.protocol.SlipDecoder
import org.pocketbot.protocol.StateFull
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.InMemorySettingsCache
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.transport.ByteStream
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.SlipStreamTransport
import org.pocketbot.sdk.transport.TcpRobotDevice
import org.pocketbot.sdk.transport.Transport
import java.lang.management.ManagementFactory
import java.net.InetSocketAddress
import java.nio.ByteBuffer
import java.nio.channels.SelectionKey
import java.nio.channels.Selector
import java.nio.channels.ServerSocketChannel
import java.nio.channels.SocketChannel
import java.util.concurrent.atomic.AtomicLong
import kotlin.time.Duration.Companion.milliseconds

/**
 * Fleet scale of the host: one JVM mirrors N robots that each send a full state 100 times a second, over TCP (real
 * loopback sockets and the SDK's TcpTransport), over TCP on ktor-network's sockets instead (the alternative the SDK's
 * own socket loop is measured against) and in process (a transport that hands over frames). The robots are
 * stand-ins that answer the handshake and then stream pre-encoded state frames from one ticker thread, so nearly all
 * the CPU the process spends is the SDK's: the robots' own threads are measured and taken off. Latency runs from the
 * moment a state frame is handed to the socket (or the transport's channel) to the collector of
 * [Robot.stateUpdates] seeing it.
 */
internal object FleetBench {
    private const val PERIOD_MS = 10
    private val SETTINGS: ByteArray = ByteArray(ProtocolInfo.SETTINGS_SIZE).also { SETTINGS_DEFAULTS.encodeTo(it, 0) }
    private val threads = ManagementFactory.getThreadMXBean()
    private val os = ManagementFactory.getOperatingSystemMXBean() as com.sun.management.OperatingSystemMXBean

    /**
     * [timed] of the [updates] the SDK delivered had their latency measured; [late] arrived more than the stamp ring
     * behind (counted in the histogram's last bucket, 100 ms and more, so they push p99 up instead of vanishing).
     */
    class Result(
        val n: Int, val transport: Link, val cores: Double, val usPerUpdate: Double, val p99Ms: Double, val updates: Long,
        val timed: Long, val late: Long, val broker: BrokerPath.Load? = null,
    )

    /** The robot side of one stand-in: what it answers to the host's frames. */
    private class Responder(val index: Int) {
        @Volatile var streaming = false

        fun answer(frame: ByteArray, out: (ByteArray) -> Unit) {
            val r = Frames.decode(frame) as? FrameResult.Decoded ?: return
            val p = r.packet
            when {
                p is HelloRequest -> out(Frames.encode(hello(), r.seq))
                PACKET_SPECS[p.type]?.acked == true -> {
                    if (p is ReadSettings) SETTINGS.toList().chunked(64).forEachIndexed { i, c ->
                        out(Frames.encode(SettingsData(i * 64, c.toByteArray()), 0))
                    }
                    if (p is ReadMovements) out(Frames.encode(MovementLog(0, 0, 0, List(16) { 0 }, List(16) { 0 }, List(16) { 0f }), 0))
                    if (p is SetSync) streaming = p.mode != 0
                    // A robot no other host drives: this host drives when it asks to.
                    if (p is SetRole) out(Frames.encode(Driver(if (p.role == 0) 0 else 1, 1, p.label, 0), 0))
                    out(Frames.encode(Ack(p.type), r.seq))
                }
            }
        }

        private fun hello() = Hello(
            index % 254 + 1, "Stand-in-$index", 0, 1, 0, ProtocolInfo.VERSION, ProtocolInfo.LAYOUT_HASH,
            ProtocolInfo.SETTINGS_SIZE, ProtocolInfo.STATE_SIZE, 0, Crc16.compute(SETTINGS),
        )
    }

    /** A full-state frame template whose robot time and CRC are patched per tick: no encoding on the hot path. */
    private class StateFrame {
        val frame: ByteArray = Frames.encode(StateFull(RobotStates.sample()), 0)

        fun at(timeMs: Long): ByteArray {
            val f = frame.copyOf()
            for (i in 0 until 4) f[Frames.HEADER_SIZE + i] = (timeMs shr (8 * i)).toByte()
            val crc = Crc16.compute(f, 0, f.size - Frames.CRC_SIZE)
            f[f.size - 2] = crc.toByte()
            f[f.size - 1] = (crc shr 8).toByte()
            return f
        }
    }

    /** Latencies in 10 us buckets up to 100 ms: no allocation per sample. */
    private class Histogram {
        private val buckets = java.util.concurrent.atomic.AtomicLongArray(10_001)
        val count = AtomicLong()

        fun add(ns: Long) {
            buckets.incrementAndGet((ns / 10_000).coerceIn(0, 10_000).toInt())
            count.incrementAndGet()
        }

        fun percentileMs(p: Double): Double {
            val target = (count.get() * p).toLong()
            var seen = 0L
            for (i in 0 until buckets.length()) {
                seen += buckets.get(i)
                if (seen > target) return (i + 1) * 0.01
            }
            return 100.0
        }
    }

    /**
     * When each robot's recent frames were sent, by robot time: a ring of the last [RING] ticks per robot, so a frame
     * that arrives after later ones were sent is still matched and timed (the tail is what p99 is for). A frame older
     * than the ring (over [RING] periods late) is counted in [late], never silently left out.
     */
    private class Stamps(n: Int) {
        private val timeMs = java.util.concurrent.atomic.AtomicLongArray(n * RING)
        private val sentNs = LongArray(n * RING)

        fun sent(robot: Int, tick: Long, time: Long, ns: Long) {
            val at = robot * RING + (tick % RING).toInt()
            sentNs[at] = ns
            timeMs.setRelease(at, time) // published after the clock reading: who sees this time sees that reading
        }

        /** The sent-at clock of [robot]'s frame of [tick] stamped [time], or -1 when it fell out of the ring. */
        fun sentAt(robot: Int, tick: Long, time: Long): Long {
            val at = robot * RING + (tick % RING).toInt()
            return if (timeMs.getAcquire(at) == time) sentNs[at] else -1
        }

        companion object {
            const val RING = 256
        }
    }

    /**
     * CPU time of the JIT compiler's threads so far (Linux: `/proc/self/task`; 0 elsewhere). A loaded machine compiles
     * the hot path late, into the measured seconds: warm-up, not what an update costs, so it is taken off too.
     */
    private fun jitCpuNanos(): Long {
        val tasks = java.io.File("/proc/self/task").listFiles() ?: return 0
        val nanosPerTick = 1_000_000_000L / 100 // USER_HZ
        return tasks.sumOf { task ->
            runCatching {
                if ("CompilerThre" !in java.io.File(task, "comm").readText()) return@runCatching 0L // C1/C2 CompilerThreadN
                val fields = java.io.File(task, "stat").readText().substringAfterLast(')').trim().split(' ')
                (fields[11].toLong() + fields[12].toLong()) * nanosPerTick // utime, stime
            }.getOrDefault(0L)
        }
    }

    /** How the host reaches the stand-ins. */
    enum class Link(val label: String, val broker: Boolean = false) {
        /** The SDK's [TcpRobotDevice]: its socket loop reads, and the robot's link runs there too. */
        TCP("tcp"),

        /**
         * The same SLIP transport on ktor-network's sockets (`SelectorManager(Dispatchers.IO)`, as ktor is meant to
         * be used): its selector wakes a reader on `Dispatchers.IO`, which hands the bytes to the robot's link.
         */
        TCP_KTOR("tcp-ktor"),

        /** Frames handed over in process: the SDK without any socket. */
        IN_PROCESS("in-process"),

        /**
         * Through one Mosquitto broker with the shipped configuration (TLS): a gateway (in this process, so the CPU
         * per update is the gateway's and the fleet client's) serves the in-process stand-ins, batching their state
         * frames (`upBatchWindow` 10 ms, the default).
         */
        BROKER("broker", broker = true),

        /** The same with every state frame in a message of its own (`upBatchWindow` 0). */
        BROKER_UNBATCHED("broker-unbatched", broker = true),
    }

    fun run(n: Int, link: Link, seconds: Int): Result = runBlocking {
        val tcp = link == Link.TCP || link == Link.TCP_KTOR
        val responders = List(n) { Responder(it) }
        val stamps = Stamps(n)
        val histogram = Histogram()
        val late = AtomicLong()
        val measuring = java.util.concurrent.atomic.AtomicBoolean(false)
        val template = StateFrame()
        val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
        val robotThreads = ArrayList<Thread>()
        val sinks = arrayOfNulls<(ByteArray) -> Unit>(n)
        val devices: List<RobotDevice>
        var server: TcpRobots? = null
        if (tcp) {
            server = TcpRobots(responders, sinks).also { robotThreads += it.thread }
            devices = if (link == Link.TCP) {
                List(n) { TcpRobotDevice("127.0.0.1", server.port(it), "stand-in-$it") }
            } else {
                List(n) { KtorTcpDevice("127.0.0.1", server.port(it), "stand-in-$it", ktorSelector) }
            }
        } else {
            devices = List(n) { i -> InProcessStandIn(responders[i]) { sinks[i] = it } }
        }
        // Through a broker: a gateway in this process serves the in-process stand-ins, the fleet reaches them over MQTT.
        val broker = if (link.broker) BrokerPath.start(devices, batched = link == Link.BROKER) else null
        val fleet = Fleet(scope, RobotOptions { settingsCache = InMemorySettingsCache() })
        val robots = fleet.connectAll(broker?.devices ?: devices)
        robots.forEach { it.reflector.set(org.pocketbot.sdk.SyncMode.FULL, PERIOD_MS.milliseconds) }
        robots.forEachIndexed { i, r ->
            scope.launch(Dispatchers.Unconfined) {
                r.stateUpdates.collect { u ->
                    val now = System.nanoTime()
                    if (!measuring.get()) return@collect
                    val tick = (u.timeMs - i % PERIOD_MS) / PERIOD_MS
                    val sent = stamps.sentAt(i, tick, u.timeMs)
                    if (sent >= 0) histogram.add(now - sent) else late.incrementAndGet()
                }
            }
        }
        // The ticker: every robot's frame once a period, robot i in the millisecond i % PERIOD_MS of it, as robots
        // whose clocks started at different moments send (not all N frames in one burst).
        val ticker = Thread({
            var ms = 0L
            val start = System.nanoTime()
            while (!Thread.currentThread().isInterrupted) {
                ms++
                val tick = ms / PERIOD_MS
                val slot = (ms % PERIOD_MS).toInt()
                for (i in slot until n step PERIOD_MS) {
                    val frame = template.at(ms)
                    stamps.sent(i, tick, ms, System.nanoTime())
                    sinks[i]?.invoke(frame)
                }
                val wait = start + ms * 1_000_000L - System.nanoTime()
                if (wait > 0) try { Thread.sleep(wait / 1_000_000, (wait % 1_000_000).toInt()) } catch (e: InterruptedException) { break }
            }
        }, "stand-in-ticker").apply { isDaemon = true; start() }
        robotThreads += ticker
        delay(2000)
        val updates0 = robots.sumOf { it.linkStats.value.fullStates }
        val cpu0 = os.processCpuTime - robotThreads.sumOf { threads.getThreadCpuTime(it.id) } - jitCpuNanos()
        val wall0 = System.nanoTime()
        broker?.measureFrom()
        measuring.set(true)
        delay(seconds * 1000L)
        measuring.set(false)
        val brokerLoad = broker?.measured()
        val wall = System.nanoTime() - wall0
        val cpu = os.processCpuTime - robotThreads.sumOf { threads.getThreadCpuTime(it.id) } - jitCpuNanos() - cpu0
        val updates = robots.sumOf { it.linkStats.value.fullStates } - updates0
        ticker.interrupt()
        fleet.disconnect()
        server?.close()
        broker?.close()
        scope.cancel()
        repeat(late.get().coerceAtMost(Int.MAX_VALUE.toLong()).toInt()) { histogram.add(Long.MAX_VALUE / 2) }
        Result(
            n, link, cpu.toDouble() / wall, cpu / 1000.0 / updates.coerceAtLeast(1),
            histogram.percentileMs(0.99), updates, histogram.count.get() - late.get(), late.get(), brokerLoad,
        )
    }

    /** ktor's selector for [Link.TCP_KTOR], on its IO dispatcher as ktor's own clients and servers use it. */
    private val ktorSelector by lazy { SelectorManager(Dispatchers.IO) }

    /** A stand-in reached through ktor-network's sockets, framed by the SDK's [SlipStreamTransport] as TCP robots are. */
    private class KtorTcpDevice(
        private val host: String, private val port: Int, override val name: String, private val selector: SelectorManager,
    ) : RobotDevice {
        override val address: String get() = "tcp://$host:$port"
        override suspend fun open(): Transport {
            val socket = withTimeout(5000) {
                aSocket(selector).tcp().connect(host, port) {
                    noDelay = true
                    keepAlive = true
                }
            }
            return SlipStreamTransport(address, KtorStream(socket), Dispatchers.Unconfined)
        }
    }

    private class KtorStream(private val socket: Socket) : ByteStream {
        private val input = socket.openReadChannel()
        private val output = socket.openWriteChannel(autoFlush = false)

        override suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int {
            while (true) {
                val n = input.readAvailable(buffer, offset, length)
                if (n != 0) return n
            }
        }

        override suspend fun write(bytes: ByteArray) {
            output.writeFully(bytes, 0, bytes.size)
            output.flush()
        }

        override fun close() {
            socket.close()
        }
    }

    /** A robot in process: frames go straight into the host's incoming channel. */
    private class InProcessStandIn(private val responder: Responder, private val attach: ((ByteArray) -> Unit) -> Unit) : RobotDevice {
        override val name: String get() = "stand-in-${responder.index}"
        override val address: String get() = "stand-in:${responder.index}"
        override suspend fun open(): Transport {
            val incoming = Channel<ByteArray>(Channel.UNLIMITED)
            attach { f -> if (responder.streaming) incoming.trySend(f) }
            return object : Transport {
                override val address: String get() = this@InProcessStandIn.address
                override val incoming: ReceiveChannel<ByteArray> get() = incoming
                override suspend fun send(frame: ByteArray) {
                    responder.answer(frame) { incoming.trySend(it) }
                }
                override fun close() {
                    incoming.close()
                }
            }
        }
    }

    /** N robots on loopback TCP ports, served by one selector thread; the ticker writes their states. */
    private class TcpRobots(private val responders: List<Responder>, private val sinks: Array<((ByteArray) -> Unit)?>) : AutoCloseable {
        private val selector = Selector.open()
        private val servers = responders.map {
            ServerSocketChannel.open().apply {
                bind(InetSocketAddress("127.0.0.1", 0))
                configureBlocking(false)
            }
        }
        private val pendingRegistrations = java.util.concurrent.ConcurrentLinkedQueue<Pair<ServerSocketChannel, Int>>()

        init {
            servers.forEachIndexed { i, s -> pendingRegistrations += s to i }
        }

        fun port(i: Int): Int = (servers[i].localAddress as InetSocketAddress).port

        val thread = Thread({ loop() }, "stand-in-tcp").apply { isDaemon = true; start() }

        private fun loop() {
            val buf = ByteBuffer.allocate(4096)
            try {
                while (!Thread.currentThread().isInterrupted) {
                    while (true) {
                        val (s, i) = pendingRegistrations.poll() ?: break
                        s.register(selector, SelectionKey.OP_ACCEPT, i)
                    }
                    selector.select(50)
                    val keys = selector.selectedKeys().iterator()
                    while (keys.hasNext()) {
                        val key = keys.next()
                        keys.remove()
                        if (key.isAcceptable) {
                            val i = key.attachment() as Int
                            val ch = (key.channel() as ServerSocketChannel).accept() ?: continue
                            ch.configureBlocking(false)
                            ch.socket().tcpNoDelay = true
                            val decoder = SlipDecoder()
                            ch.register(selector, SelectionKey.OP_READ, i).also { it.attach(i to decoder) }
                            val write: (ByteArray) -> Unit = { f -> writeFully(ch, Slip.encode(f)) }
                            sinks[i] = { f -> if (responders[i].streaming) runCatching { write(f) } }
                        } else if (key.isReadable) {
                            @Suppress("UNCHECKED_CAST")
                            val (idx, decoder) = key.attachment() as Pair<Int, SlipDecoder>
                            val ch = key.channel() as SocketChannel
                            buf.clear()
                            val n = try { ch.read(buf) } catch (e: java.io.IOException) { -1 }
                            if (n < 0) { key.cancel(); ch.close(); continue }
                            try {
                                decoder.feed(buf.array(), 0, n) { frame -> responders[idx].answer(frame) { writeFully(ch, Slip.encode(it)) } }
                            } catch (e: java.io.IOException) {
                                key.cancel() // the host left while answered (its goodbye's ack): the other robots go on
                                ch.close()
                            }
                        }
                    }
                }
            } catch (_: java.nio.channels.ClosedSelectorException) {
            }
        }

        private fun writeFully(ch: SocketChannel, bytes: ByteArray) {
            synchronized(ch) {
                val b = ByteBuffer.wrap(bytes)
                while (b.hasRemaining()) if (ch.write(b) == 0) Thread.onSpinWait()
            }
        }

        override fun close() {
            thread.interrupt()
            runCatching { selector.close() }
            servers.forEach { runCatching { it.close() } }
        }
    }
}

/** A plausible robot state to stream (values do not matter to the cost; the robot time is patched per frame). */
internal object RobotStates {
    fun sample(): org.pocketbot.protocol.RobotState {
        val bytes = ByteArray(ProtocolInfo.STATE_SIZE) { (it * 7).toByte() }
        return org.pocketbot.protocol.RobotState.decode(bytes, 0)
    }
}
