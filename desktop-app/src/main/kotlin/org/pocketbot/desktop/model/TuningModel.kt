package org.pocketbot.desktop.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.CoroutineStart
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.flow.filter
import kotlinx.coroutines.flow.update
import kotlinx.coroutines.launch
import org.pocketbot.sdk.Controller
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.StateUpdate
import org.pocketbot.sdk.StepResponse
import org.pocketbot.sdk.StepSize
import org.pocketbot.sdk.Tuner
import org.pocketbot.sdk.TuningSample
import java.util.concurrent.atomic.AtomicLong
import kotlin.time.Duration

/**
 * A fixed-size ring of the newest tuning samples. The SDK's collector adds every sample; the chart takes a
 * [snapshot] once per frame, so drawing never slows the collection down and no sample is skipped.
 */
class SampleRing(val capacity: Int) {
    private val time = LongArray(capacity)
    private val setpoint = DoubleArray(capacity)
    private val measured = DoubleArray(capacity)
    private var next = 0
    private var size = 0

    /** Samples added since the start. */
    val added = AtomicLong()

    @Synchronized fun add(s: TuningSample) {
        time[next] = s.timeMs
        setpoint[next] = s.setpoint
        measured[next] = s.measured
        next = (next + 1) % capacity
        if (size < capacity) size++
        added.incrementAndGet()
    }

    @Synchronized fun clear() { next = 0; size = 0 }

    /** The newest samples within [spanMs] of robot time, as chart columns: seconds before the newest, setpoint, measured. */
    @Synchronized fun window(spanMs: Long): Window {
        if (size == 0) return Window(DoubleArray(0), DoubleArray(0), DoubleArray(0))
        val newest = time[(next - 1 + capacity) % capacity]
        var n = 0
        while (n < size && newest - time[(next - 1 - n + 2 * capacity) % capacity] <= spanMs) n++
        val x = DoubleArray(n); val sp = DoubleArray(n); val m = DoubleArray(n)
        for (i in 0 until n) {
            val k = (next - n + i + 2 * capacity) % capacity
            x[i] = (time[k] - newest) / 1000.0; sp[i] = setpoint[k]; m[i] = measured[k]
        }
        return Window(x, sp, m)
    }

    /** Chart columns of a [window]: no object per sample, so a frame allocates three arrays and nothing else. */
    class Window(val seconds: DoubleArray, val setpoint: DoubleArray, val measured: DoubleArray)

    /** The samples held, oldest first. */
    @Synchronized fun snapshot(): List<TuningSample> = List(size) { i ->
        val k = (next - size + i + capacity) % capacity
        TuningSample(time[k], setpoint[k], measured[k])
    }
}

/** The step responses of one controller: the latest, the reference beside it, and whether the reference is frozen. */
class Captures(val latest: StepResponse? = null, val reference: StepResponse? = null, val frozen: Boolean = false)

/**
 * PID tuning of one robot, for the tuning view: while [active], the robot sends reduced state every [samplePeriod]
 * and every sample of the chosen [controller] goes into [live]; a step test (of a size the user chose and confirmed)
 * captures a [StepResponse], which can be frozen beside the previous one. Each controller keeps its own captures: the
 * view shows the chosen controller's only.
 */
class TuningModel(private val robot: Robot, private val scope: CoroutineScope, private val notify: (String) -> Unit) {
    private val tuner = Tuner(robot)
    private val _controller = MutableStateFlow(Controller.ROBOT_SPEED)
    private val _active = MutableStateFlow(false)
    private val _running = MutableStateFlow(false)
    private val _captures = MutableStateFlow<Map<Controller, Captures>>(emptyMap())
    private val _stepSizes = MutableStateFlow(Controller.entries.associateWith(StepSize::defaultFor))
    private var collector: Job? = null
    @Volatile private var left = false

    /** How often the robot sends a sample while tuned: as fast as its link carries ([Tuner.samplePeriod]). */
    val samplePeriod: Duration get() = tuner.samplePeriod

    /** The newest samples of the controller, about 10 s at the tuning rate. */
    val live = SampleRing(LIVE_SAMPLES)

    /** Reduced states the robot sent (link counter) when the live chart started: with [live]'s count, shows none was lost. */
    @Volatile var reducedAtStart: Long = 0
        private set

    val controller: StateFlow<Controller> = _controller.asStateFlow()
    val active: StateFlow<Boolean> = _active.asStateFlow()

    /** True while a step test runs. */
    val running: StateFlow<Boolean> = _running.asStateFlow()

    /** Every controller's step responses (see [capturesOf]). */
    val captures: StateFlow<Map<Controller, Captures>> = _captures.asStateFlow()

    /** The step size each controller's next step test runs, as last chosen. */
    val stepSizes: StateFlow<Map<Controller, StepSize>> = _stepSizes.asStateFlow()

    /** The step responses of [controller]: none until its first step test. */
    fun capturesOf(controller: Controller): Captures = _captures.value[controller] ?: Captures()

    /** The latest step response of the chosen controller. */
    val captured: StepResponse? get() = capturesOf(_controller.value).latest

    /** Starts the live chart of [controller]: the robot switches to fast reduced state. */
    fun start(controller: Controller = _controller.value) {
        _controller.value = controller
        collector?.cancel()
        live.clear()
        _active.value = true
        collector = scope.launch {
            try {
                // Subscribed before the robot switches, and counted against the link's counter from the same moment:
                // the chart's count equals the robot's reduced states unless a sample was really lost on the way.
                live.added.set(0)
                reducedAtStart = robot.linkStats.value.reducedStates
                launch(start = CoroutineStart.UNDISPATCHED) {
                    robot.stateUpdates.filter { it.kind == StateUpdate.Kind.REDUCED }.collect { live.add(tuner.sampleOf(controller, it)) }
                }
                tuner.begin()
            } catch (e: CancellationException) {
                throw e
            } catch (e: Exception) {
                _active.value = false
                notify("${robot.identity.name}: tuning: ${e.message ?: e}")
            }
        }
    }

    /** Switches the chart to [controller]; its own step responses show. */
    fun choose(controller: Controller) { if (_active.value) start(controller) else _controller.value = controller }

    /** Ends the live chart; the robot gets its sync mode back. */
    suspend fun stop() {
        collector?.cancel()
        collector = null
        if (_active.value) {
            _active.value = false
            try { tuner.end() } catch (e: CancellationException) { throw e } catch (_: Exception) { /* link gone: nothing to restore */ }
        }
    }

    fun stopLater() { scope.launch { stop() } }

    /** The user opened the tuning view (again): a step test that runs there keeps the robot tuned when it ends. */
    fun enter() {
        left = false
    }

    /**
     * The user left the tuning view: the robot goes back to its sync mode (full state for every other view) at once,
     * or when the step test that runs has ended.
     */
    fun leave() {
        left = true
        if (!_running.value) stopLater()
    }

    /**
     * Runs the chosen controller's manoeuvre at [size] (the user confirmed what [StepSize.describe] says the robot will
     * do) and captures its response. The robot moves.
     */
    fun stepTest(size: StepSize = _stepSizes.value.getValue(_controller.value)) {
        if (_running.value) return
        _running.value = true
        val controller = _controller.value
        _stepSizes.update { it + (controller to size) }
        scope.launch {
            try {
                if (!_active.value) start()
                val response = tuner.stepTest(controller, size)
                _captures.update { all ->
                    val c = all[controller] ?: Captures()
                    all + (controller to Captures(response, if (c.frozen) c.reference else c.latest, c.frozen))
                }
            } catch (e: CancellationException) {
                throw e
            } catch (e: Exception) {
                notify("${robot.identity.name}: step test: ${e.message ?: e}")
            } finally {
                _running.value = false
                if (left) stop()
            }
        }
    }

    /** Keeps the chosen controller's current capture as the overlay's reference (or lets it go again). */
    fun toggleFreeze() = _captures.update { all ->
        val controller = _controller.value
        val c = all[controller] ?: Captures()
        all + (controller to if (c.frozen) Captures(c.latest, c.reference, false) else Captures(c.latest, c.latest, true))
    }

    /** The gain [name] (kp, ki, kd) of the chosen controller, changed by [factor] (the +/- buttons). */
    fun stepGain(name: String, factor: Double, write: (String, String) -> Unit) {
        val gains = _controller.value.gains(robot.settings)
        val field = when (name) { "kp" -> gains.kp; "ki" -> gains.ki; else -> gains.kd }
        val now = field.value
        val next = if (now == 0.0) (if (factor > 1) GAIN_FROM_ZERO else 0.0) else now * factor
        write(field.name, field.format(next))
    }

    companion object {
        const val LIVE_SAMPLES = 2500
        private const val GAIN_FROM_ZERO = 0.01
    }
}
