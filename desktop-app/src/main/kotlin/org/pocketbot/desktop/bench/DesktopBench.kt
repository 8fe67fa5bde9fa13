package org.pocketbot.desktop.bench

import androidx.compose.runtime.mutableStateOf
import androidx.compose.ui.ImageComposeScene
import androidx.compose.ui.InternalComposeUiApi
import androidx.compose.ui.graphics.asComposeCanvas
import androidx.compose.ui.scene.ComposeScene
import androidx.compose.ui.unit.Density
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.jetbrains.skia.PictureRecorder
import org.jetbrains.skia.Rect
import org.jetbrains.skia.Surface
import org.pocketbot.desktop.model.EmulatorModel
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.ui.PanelApp
import org.pocketbot.desktop.ui.View
import org.pocketbot.sdk.ColourMode
import org.pocketbot.sdk.Controller
import org.pocketbot.sdk.SyncMode
import java.lang.management.ManagementFactory
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/**
 * `make bench-desktop`: the panel with 7 robots at 100 Hz full state and one tuned robot in reduced mode at the
 * fastest period its link carries ([org.pocketbot.sdk.Tuner.samplePeriod]), drawn off screen at 60 frames a second.
 * Prints, as `desktop <metric>=<value>`:
 * the share of the tuned robot's samples that reached the chart over the whole run (goal 100 %), and the composition +
 * layout + drawing time of a frame (p50, p95; goal p95 <= 16 ms), on the tuning view and on the fleet overview, and
 * the CPU time the rendering thread spent on it.
 *
 * Both views are first rendered unmeasured for `--warmup` seconds each: until then the JIT compiles the panel's code on
 * the same two cores (a C2 compiler thread at a third of a core 10 s in) and the tuning chart is still filling.
 *
 * Arguments: `--seconds N` per view (default 10); `--warmup N` per view (default 5); `--phases` times each step of a
 * frame instead (see [Phases]).
 */
fun main(args: Array<String>): Unit = runBlocking {
    fun option(name: String, default: Int) = args.indexOf(name).takeIf { it >= 0 }?.let { args[it + 1].toInt() } ?: default
    val seconds = option("--seconds", 10)
    val warmup = option("--warmup", 5)
    val phased = "--phases" in args
    val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    val emulator = EmulatorModel(scope, "round", robots = 8)
    val panel = PanelModel(scope, emptyMap(), emulator)
    try {
        val robots = withTimeout(60.seconds) { panel.connectEmbedded() }
        check(robots.size == 8) { "connected ${robots.size} of 8 robots" }
        val tuned = robots.first()
        for (r in robots.drop(1)) {
            r.robot.reflector.set(SyncMode.FULL, 10.milliseconds)
            r.startLineFollowing(0.15, ColourMode.PLAIN)
        }
        panel.select(tuned)
        tuned.tuning.choose(Controller.LINE)
        tuned.startLineFollowing(0.15, ColourMode.PLAIN)
        tuned.tuning.start()
        tuned.tuning.active.first { it }
        delay(500)

        val view = mutableStateOf(View.TUNING)
        val scene = ImageComposeScene(1440, 900, Density(1f)) { PanelApp(panel, view) }
        val phases = if (phased) listOf(Phases(scene, 1440, 900), Phases(scene, 1440, 900)) else listOf(null, null)
        try {
            frames(scene, warmup)
            view.value = View.OVERVIEW
            frames(scene, warmup)
            view.value = View.TUNING
            val tuning = frames(scene, seconds, phases[0])
            view.value = View.OVERVIEW
            val overview = frames(scene, seconds, phases[1])
            // Every sample since the tuning started, against every reduced state the link counted since then: the
            // robot back in full state first (the chart still collecting), so none is on its way when they are read.
            tuned.robot.reflector.set(SyncMode.FULL, 10.milliseconds)
            delay(500)
            val charted = tuned.tuning.live.added.get()
            val sent = tuned.robot.linkStats.value.reducedStates - tuned.tuning.reducedAtStart
            println("desktop robots=8 (7 at 100 Hz full state, 1 tuned at ${1000 / tuned.tuning.samplePeriod.inWholeMilliseconds} Hz reduced)")
            println("desktop tuned_samples_sent=$sent")
            println("desktop tuned_samples_charted_pct=%.2f".format(100.0 * charted / sent))
            for ((name, f) in listOf("tuning" to tuning, "overview" to overview)) {
                println("desktop ${name}_frame_ms_p50=%.2f".format(f.wall.percentile(50)))
                println("desktop ${name}_frame_ms_p95=%.2f".format(f.wall.percentile(95)))
                println("desktop ${name}_frame_cpu_ms_p50=%.2f".format(f.cpu.percentile(50)))
                println("desktop ${name}_frame_cpu_ms_p95=%.2f".format(f.cpu.percentile(95)))
            }
            phases[0]?.print("tuning")
            phases[1]?.print("overview")
        } finally {
            scene.close()
        }
    } finally {
        panel.close()
        scope.cancel()
    }
}

/** The wall-clock time each frame took to render, and the CPU time the rendering thread spent on it, in ms. */
private class Frames(val wall: DoubleArray, val cpu: DoubleArray)

/**
 * Renders a frame every 1/60 s for [seconds]. The CPU time sets the figures of two runs side by side on a machine
 * that other work shares (the wall-clock time counts the moments the thread waited for a core); the goal is on the
 * wall-clock time.
 */
private suspend fun frames(scene: ImageComposeScene, seconds: Int, phases: Phases? = null): Frames {
    val threads = ManagementFactory.getThreadMXBean()
    val wall = ArrayList<Double>()
    val cpu = ArrayList<Double>()
    val start = System.nanoTime()
    var next = start
    while (System.nanoTime() - start < seconds * 1_000_000_000L) {
        val t0 = System.nanoTime()
        val c0 = threads.currentThreadCpuTime
        // The image is closed at once, as a window shows its frame and draws the next one into the same pixels: an
        // image kept alive makes the next frame copy the whole surface first (copy on write, 3-4 ms at 1440 x 900).
        if (phases != null) phases.render(t0 - start) else scene.render(t0 - start).close()
        cpu += (threads.currentThreadCpuTime - c0) / 1e6
        wall += (System.nanoTime() - t0) / 1e6
        next += 16_666_667
        val wait = (next - System.nanoTime()) / 1_000_000
        if (wait > 0) delay(wait) else next = System.nanoTime()
    }
    // The first frames compose everything for the first time.
    return Frames(wall.drop(30).toDoubleArray(), cpu.drop(30).toDoubleArray())
}

private fun DoubleArray.percentile(p: Int): Double = sorted()[((size - 1) * p / 100.0).toInt()]

/**
 * [ImageComposeScene.render] split into its steps, each timed (`--phases`): the surface cleared, composition (the
 * frame clock's frame: recomposition and effects), measure and layout, drawing recorded into a picture (the
 * composables' draw code), the picture rasterized (Skia, in software), the image snapshot. Reaches into the scene's
 * private fields: a profiling aid for this Compose version, not part of the benchmark's figures.
 */
@OptIn(InternalComposeUiApi::class)
private class Phases(private val scene: ImageComposeScene, private val width: Int, private val height: Int) {
    private fun field(name: String): Any = ImageComposeScene::class.java.getDeclaredField(name).apply { isAccessible = true }.get(scene)
    private val surface = field("surface") as Surface
    private val recomposer = field("frameRecomposer")
    private val performFrame = recomposer.javaClass.getMethod("performFrame", Long::class.javaPrimitiveType)
    private val inner = field("scene") as ComposeScene
    val names = listOf("clear", "compose", "layout", "record", "raster", "snapshot")
    val times = names.associateWith { ArrayList<Double>() }

    fun render(nanoTime: Long) {
        var t = System.nanoTime()
        fun lap(name: String) { val now = System.nanoTime(); times.getValue(name) += (now - t) / 1e6; t = now }
        surface.canvas.clear(0)
        lap("clear")
        performFrame.invoke(recomposer, nanoTime)
        lap("compose")
        inner.measureAndLayout()
        lap("layout")
        val recorder = PictureRecorder()
        inner.draw(recorder.beginRecording(Rect.makeWH(width.toFloat(), height.toFloat())).asComposeCanvas())
        val picture = recorder.finishRecordingAsPicture()
        lap("record")
        picture.playback(surface.canvas)
        lap("raster")
        picture.close()
        recorder.close()
        surface.makeImageSnapshot().close()
        lap("snapshot")
    }

    fun print(view: String) {
        for (n in names) {
            val a = times.getValue(n).drop(30).toDoubleArray()
            println("desktop ${view}_${n}_ms_p50=%.2f".format(a.percentile(50)))
            println("desktop ${view}_${n}_ms_p95=%.2f".format(a.percentile(95)))
        }
    }
}

