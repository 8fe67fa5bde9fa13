package org.pocketbot.desktop.model

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.isActive
import kotlinx.coroutines.launch
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.RobotHandle
import org.pocketbot.emulator.Speed
import org.pocketbot.emulator.transport.ListenAddress
import org.pocketbot.emulator.world.World
import org.pocketbot.emulator.world.Worlds
import org.pocketbot.protocol.LedFlags
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.Trajectory
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.pocketbot.sdk.transport.RobotDevice
import java.io.IOException
import java.net.InetAddress
import java.net.InetSocketAddress

/**
 * One emulated robot as the world view draws it: its true pose, the path it really took, and its status LEDs ([led],
 * bits of [org.pocketbot.protocol.LedFlags]: the track token's orange light among them).
 */
class TrueRobot(val id: Int, val address: String, val pose: Pose, val path: Trajectory, val led: Int = 0) {
    /** The robot holds the track token (thesis A.3): its orange light is on. */
    val holdsToken: Boolean get() = led and LedFlags.TOKEN != 0
}

/**
 * The embedded emulator served on the network: its robots and control port listen on [listen], the control port at
 * [controlPort]; [addresses] (`host:port` of the control port) are what a phone or another computer types in.
 */
class Serving(val listen: InetAddress, val controlPort: Int, val addresses: List<String>)

/** What the world view shows of the emulator at one moment. */
class WorldSnapshot(val world: World, val timeMs: Long, val robots: List<TrueRobot>, val boxes: List<Pose>)

/**
 * The embedded emulator: the real firmware on simulated robots in a shipped world or a world file, run in real time
 * (or faster) on its own thread. The panel finds its robots like any others, through [discoverer].
 *
 * [serve] puts its robots on the network as well (TCP endpoints and a control port, as `make emulator` has them), so a
 * phone drives a robot the panel draws. Each robot serves several hosts at once: the panel and a phone both see it,
 * and the robot lets one of them drive (the other watches until it takes over or the driver leaves).
 */
class EmulatorModel(
    private val scope: CoroutineScope,
    world: String = "round",
    robots: Int = 3,
    speed: Double = 1.0,
    /** Where [serve] listens: every address of this machine, on the usual control port, unless told otherwise. */
    val serveAt: InetSocketAddress = InetSocketAddress(ListenAddress.ANY, EmulatorDiscoverer.DEFAULT_CONTROL_PORT),
) : AutoCloseable {
    private var emulator: Emulator = start(Worlds.load(world), robots, speed)
    private val paths = HashMap<Int, Trajectory>()
    private val _snapshot = MutableStateFlow(snapshot())
    private val _paused = MutableStateFlow(false)
    private val _speed = MutableStateFlow(speed)
    private val _serving = MutableStateFlow<Serving?>(null)
    private var sampler: Job = sample()

    /** The world and every robot's true pose, about 30 times a second. */
    val world: StateFlow<WorldSnapshot> = _snapshot.asStateFlow()

    val paused: StateFlow<Boolean> = _paused.asStateFlow()

    /** Simulated seconds per wall-clock second. */
    val speed: StateFlow<Double> = _speed.asStateFlow()

    /** The network address the emulator is served at, or null while only the panel reaches it. */
    val serving: StateFlow<Serving?> = _serving.asStateFlow()

    /** Finds the robots of the emulator running now, in process. */
    val discoverer: Discoverer = object : Discoverer {
        override fun discover(): Flow<RobotDevice> = emulator.discoverer().discover()
    }

    /**
     * Serves the emulator's robots on the network at [serveAt] (robot i on the control port + i, as the emulator's
     * command line does) until [stopServing]. Throws [IOException] when it cannot listen there (a port taken, an
     * address that is not this machine's).
     */
    fun serve() {
        serveOn(emulator)
    }

    private fun serveOn(e: Emulator) {
        val port = serveAt.port
        val control = e.startTcp(basePort = if (port == 0) 0 else port + 1, controlPort = port, listen = serveAt.address)
        val reachable = ListenAddress.reachable(serveAt.address).map { "${ListenAddress.hostText(it)}:$control" }
        _serving.value = Serving(serveAt.address, control, reachable)
    }

    /** Takes the robots off the network; hosts connected there lose the link. */
    fun stopServing() {
        emulator.stopTcp()
        _serving.value = null
    }

    /** The emulated robot behind a connected robot's [address], or null when it is not one of ours. */
    fun handleFor(address: String): RobotHandle? = emulator.robots.firstOrNull { it.address == address }

    /** The ids of the shipped worlds. */
    val shippedWorlds: List<String> get() = Worlds.names

    fun pause() { emulator.pause(); _paused.value = true }
    fun resume() { emulator.resume(); _paused.value = false }

    /** Pauses and advances the simulation by one step (1 ms). */
    fun singleStep() {
        pause()
        emulator.singleStep()
        _snapshot.value = snapshot()
    }

    fun setSpeed(factor: Double) {
        require(factor > 0) { "speed must be positive" }
        emulator.speed = Speed.Realtime(factor)
        _speed.value = factor
    }

    /** The path the emulated robot at [address] really took (since the last [clearPaths]), or null when it is not ours. */
    fun truePath(address: String): Trajectory? {
        val id = handleFor(address)?.id ?: return null
        return synchronized(paths) { paths[id] }
    }

    /** Forgets the true paths drawn so far. */
    fun clearPaths() = synchronized(paths) { paths.values.forEach { it.clear() } }

    /** Loads [world] (a shipped name or a world file); [IllegalArgumentException] says what is wrong with it. */
    fun load(world: String): World = try {
        Worlds.load(world)
    } catch (e: IllegalArgumentException) {
        throw e
    } catch (e: Exception) {
        throw IllegalArgumentException(e.message ?: e.toString(), e)
    }

    /**
     * Replaces the emulator by a new one running [spec] with [robots] robots. Robots connected to the old emulator
     * lose their link: disconnect them first.
     */
    fun restart(spec: World, robots: Int) {
        require(robots in 1..MAX_ROBOTS) { "robots must be 1..$MAX_ROBOTS" }
        sampler.cancel()
        emulator.close()
        synchronized(paths) { paths.clear() }
        emulator = start(spec, robots, _speed.value)
        _paused.value = false
        _snapshot.value = snapshot()
        sampler = sample()
        if (_serving.value != null) {
            try {
                serveOn(emulator)
            } catch (e: IOException) {
                _serving.value = null
                throw e
            }
        }
    }

    private fun start(world: World, robots: Int, speed: Double): Emulator =
        Emulator(world).also { e ->
            repeat(robots) { e.addRobot() }
            e.start(Speed.Realtime(speed))
        }

    private fun sample(): Job = scope.launch {
        while (isActive) {
            _snapshot.value = snapshot()
            delay(SAMPLE_MS)
        }
    }

    private fun snapshot(): WorldSnapshot {
        val e = emulator
        val robots = e.robots.map { h ->
            val pose = h.truePose
            val path = synchronized(paths) { paths.getOrPut(h.id) { Trajectory() } }
            val timeMs = e.time.inWholeMilliseconds
            path.add(timeMs, pose)
            TrueRobot(h.id, h.address, pose, path, h.led)
        }
        return WorldSnapshot(e.world, e.time.inWholeMilliseconds, robots, e.boxes())
    }

    override fun close() {
        sampler.cancel()
        emulator.close()
    }

    companion object {
        const val MAX_ROBOTS = 20
        private const val SAMPLE_MS = 33L
    }
}
