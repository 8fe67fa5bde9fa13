package org.pocketbot.desktop.ui

import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.ExperimentalLayoutApi
import androidx.compose.foundation.layout.FlowRow
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxHeight
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.width
import androidx.compose.material3.Button
import androidx.compose.material3.FilterChip
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.OutlinedTextField
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.DisposableEffect
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.graphicsLayer
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.unit.dp
import kotlinx.coroutines.delay
import org.pocketbot.desktop.model.EditStatus
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.sdk.Controller
import org.pocketbot.sdk.StepResponse
import org.pocketbot.sdk.StepSize
import org.pocketbot.sdk.toDecimalString
import kotlin.time.Duration.Companion.milliseconds

private val setpointColour = Color(0xFF9E9E9E)
private val measuredColour = Color(0xFF1565C0)
private val previousColour = Color(0xFFEF6C00)
private const val FRAME_MS = 16L
private const val LIVE_SPAN_MS = 5000L

/**
 * PID tuning (QGroundControl-style): the chosen controller's setpoint and measured value on a scrolling chart at the
 * fastest rate the link carries, its gains beside it with +/- steps and typed entry, and a step test (of a size the
 * user chooses, and asked before the robot moves) whose response can be frozen, overlaid with the previous one and
 * exported. Each controller shows its own responses. Leaving the view gives the robot its sync mode back.
 */
@OptIn(ExperimentalLayoutApi::class)
@Composable
fun TuningView(robot: RobotModel) {
    val tuning = robot.tuning
    val controller by tuning.controller.collectAsState()
    val active by tuning.active.collectAsState()
    val running by tuning.running.collectAsState()
    val captures by tuning.captures.collectAsState()
    val mine = captures[controller]
    val captured = mine?.latest
    val previous = mine?.reference
    val frozen = mine?.frozen == true
    var asking by remember(robot) { mutableStateOf(false) }
    DisposableEffect(robot) {
        tuning.enter()
        onDispose { tuning.leave() }
    }
    Row(horizontalArrangement = Arrangement.spacedBy(12.dp)) {
        Column(Modifier.weight(1f), verticalArrangement = Arrangement.spacedBy(8.dp)) {
            Text("${robot.name}: PID tuning", style = MaterialTheme.typography.titleLarge)
            // Wraps in a narrow window rather than squeezing the title and pushing the rest out of view.
            FlowRow(horizontalArrangement = Arrangement.spacedBy(6.dp)) {
                for (c in Controller.entries) FilterChip(controller == c, { tuning.choose(c) }, { Text(c.title) }, Modifier.testTag("controller-${c.name}"))
            }
            Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
                if (active) OutlinedButton(onClick = { tuning.stopLater() }, Modifier.testTag("tuning-stop")) { Text("Stop live chart") }
                else Button(onClick = { tuning.start() }, Modifier.testTag("tuning-start")) { Text("Start live chart") }
                Button(onClick = { asking = true }, enabled = !running && !asking, modifier = Modifier.testTag("step-test")) {
                    Text(if (running) "Step test running" else "Step test...")
                }
                LiveCount(robot)
            }
            if (asking) StepQuestion(robot, controller, onAnswer = { size -> asking = false; size?.let(tuning::stepTest) })
            LiveChart(robot, controller, Modifier.weight(1f).fillMaxWidth())
            Text("Step response" + (captured?.let { " · ${figures(it)}" } ?: ": run a step test"), Modifier.testTag("step-figures"),
                style = MaterialTheme.typography.titleSmall)
            Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                OutlinedButton(onClick = { tuning.toggleFreeze() }, enabled = captured != null, modifier = Modifier.testTag("tuning-freeze")) { Text(if (frozen) "Unfreeze" else "Freeze as reference") }
                OutlinedButton(onClick = { captured?.let { c -> chooseFile("Export step response CSV", true, "step-${c.controller.name.lowercase()}.csv")?.writeText(c.toCsv()) } },
                    enabled = captured != null) { Text("Export CSV") }
                OutlinedButton(onClick = {
                    val c = captured ?: return@OutlinedButton
                    chooseFile("Export step response PNG", true, "step-${c.controller.name.lowercase()}.png")?.let { f ->
                        exportPng(f, 900, 450) { drawChart(stepSeries(c, previous), "s", null, offscreenTextMeasurer, Color.DarkGray) }
                    }
                }, enabled = captured != null) { Text("Export PNG") }
            }
            LineChart(captured?.let { stepSeries(it, previous) } ?: emptyList(), "s", Modifier.weight(1f).fillMaxWidth().testTag("step-chart"))
        }
        Gains(robot, controller, Modifier.width(280.dp).fillMaxHeight())
    }
}

/**
 * Before a step test: its size (speed, and distance or duration), what the robot will do at that size, and the user's
 * go-ahead ([onAnswer] with the size) or cancel ([onAnswer] with null). The robot does not move until then.
 */
@Composable
private fun StepQuestion(robot: RobotModel, controller: Controller, onAnswer: (StepSize?) -> Unit) {
    val last = robot.tuning.stepSizes.collectAsState().value.getValue(controller)
    var speed by remember(controller) { mutableStateOf(last.speedMps.toDecimalString()) }
    var distance by remember(controller) { mutableStateOf(last.distanceM.toDecimalString()) }
    var seconds by remember(controller) { mutableStateOf((last.duration.inWholeMilliseconds / 1000.0).toDecimalString()) }
    val moves = controller == Controller.ROBOT_SPEED || controller == Controller.WHEEL_BALANCE
    // A number that is no number is a NumberFormatException, an IllegalArgumentException as StepSize's own checks are.
    val (size, problem) = try {
        StepSize(speed.trim().toDouble(), if (moves) distance.trim().toDouble() else last.distanceM,
            if (moves) last.duration else (seconds.trim().toDouble() * 1000).toLong().milliseconds) to null
    } catch (e: IllegalArgumentException) {
        null to (e.message ?: "not a number")
    }
    Panel("Step test: ${controller.title}", Modifier.fillMaxWidth()) {
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            OutlinedTextField(speed, { speed = it }, Modifier.width(130.dp).testTag("step-speed"), singleLine = true, label = { Text("speed m/s") })
            if (moves) OutlinedTextField(distance, { distance = it }, Modifier.width(130.dp).testTag("step-distance"), singleLine = true, label = { Text("distance m") })
            else OutlinedTextField(seconds, { seconds = it }, Modifier.width(130.dp).testTag("step-seconds"), singleLine = true, label = { Text("duration s") })
        }
        Text(size?.let { "${robot.name} ${it.describe(controller)}. Give it room." } ?: problem.orEmpty(), Modifier.testTag("step-describe"),
            color = if (size == null) MaterialTheme.colorScheme.error else Color.Unspecified, style = MaterialTheme.typography.bodyMedium)
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            Button(onClick = { onAnswer(size) }, enabled = size != null, modifier = Modifier.testTag("step-confirm")) { Text("Run the step test") }
            OutlinedButton(onClick = { onAnswer(null) }, Modifier.testTag("step-cancel")) { Text("Cancel") }
        }
    }
}

/** How many samples reached the chart, against how many reduced states the robot sent meanwhile. */
@Composable
private fun LiveCount(robot: RobotModel) {
    robot.robot.linkStats.collectAtHumanRate().value // recomposes as samples arrive, at a rate people read
    val active by robot.tuning.active.collectAsState()
    if (!active) return
    // Charted first, then the link's count as it is now (the collected value may be a frame behind): the link counts
    // a sample before the chart can have it, so "charted" never runs ahead of "sent".
    val charted = robot.tuning.live.added.get()
    val sent = robot.robot.linkStats.value.reducedStates - robot.tuning.reducedAtStart
    Text("$charted samples charted of $sent sent", Modifier.graphicsLayer().testTag("tuning-count"), style = MaterialTheme.typography.bodySmall)
}

/** The live chart: the last five seconds of robot time, redrawn once per frame from the sample ring. */
@Composable
private fun LiveChart(robot: RobotModel, controller: Controller, modifier: Modifier) {
    // Read while drawing only: a new window redraws the chart's canvas, and nothing is composed or laid out again.
    val window = remember(robot) { mutableStateOf(robot.tuning.live.window(LIVE_SPAN_MS)) }
    LaunchedEffect(robot, controller) {
        var seen = -1L
        while (true) {
            val n = robot.tuning.live.added.get()
            if (n != seen) { seen = n; window.value = robot.tuning.live.window(LIVE_SPAN_MS) }
            delay(FRAME_MS) // about one frame: the ring keeps every sample meanwhile
        }
    }
    val measured = "measured ${controller.title}" + if (controller.unit.isEmpty()) "" else " (${controller.unit})"
    val legend = listOf("setpoint" to setpointColour, measured to measuredColour)
    LineChart({
        val w = window.value
        listOf(Series("setpoint", w.seconds, w.setpoint, setpointColour), Series(measured, w.seconds, w.measured, measuredColour))
    }, legend, "live chart of setpoint and $measured, the last ${LIVE_SPAN_MS / 1000} s", "s", modifier.testTag("live-chart"))
}

private fun stepSeries(now: StepResponse, previous: StepResponse?): List<Series> {
    fun series(r: StepResponse, label: String, colour: Color, dashed: Boolean): List<Series> {
        val t0 = r.samples.firstOrNull()?.timeMs ?: 0
        val x = DoubleArray(r.samples.size) { (r.samples[it].timeMs - t0) / 1000.0 }
        return listOf(
            Series("$label setpoint", x, DoubleArray(r.samples.size) { r.samples[it].setpoint }, setpointColour, dashed),
            Series("$label measured", x, DoubleArray(r.samples.size) { r.samples[it].measured }, colour, dashed),
        )
    }
    return series(now, "this run", measuredColour, false) +
        (previous?.takeIf { it !== now }?.let { series(it, "reference", previousColour, true) } ?: emptyList())
}

private fun figures(r: StepResponse): String = listOfNotNull(
    "${r.samples.size} samples",
    r.riseTimeMs?.let { "rise $it ms" },
    r.overshootPercent?.let { "overshoot %.1f %%".format(it) },
    "rms error %.4f".format(r.rmsError),
    "gains kp ${r.gains[0].toFloat().toDecimalString()} ki ${r.gains[1].toFloat().toDecimalString()} kd ${r.gains[2].toFloat().toDecimalString()}",
).joinToString(" · ")

/** The controller's gains: typed entry and x1.25 / x0.8 steps, each written to the robot at once. */
@Composable
private fun Gains(robot: RobotModel, controller: Controller, modifier: Modifier) {
    val values by robot.robot.settings.values.collectAsState()
    val edits by robot.edits.collectAsState()
    val gains = controller.gains(robot.robot.settings)
    Panel("Gains: ${controller.title}", modifier) {
        for (field in listOf(gains.kp, gains.ki, gains.kd, gains.iLimit)) {
            val current = remember(values, field) { field.valueText }
            var text by remember(field, current) { mutableStateOf(current) }
            val short = field.name.substringAfter('.')
            Row(verticalAlignment = Alignment.CenterVertically) {
                OutlinedTextField(text, { text = it }, Modifier.width(140.dp).testTag("gain-$short"), singleLine = true, label = { Text(short) })
                TextButton(onClick = { robot.write(field.name, text) }) { Text("Set") }
                if (short != "i_limit") {
                    TextButton(onClick = { robot.tuning.stepGain(short, 0.8, robot::write) }, Modifier.width(36.dp).testTag("gain-down-$short")) { Text("-") }
                    TextButton(onClick = { robot.tuning.stepGain(short, 1.25, robot::write) }, Modifier.width(36.dp).testTag("gain-up-$short")) { Text("+") }
                }
            }
            when (val s = edits[field.name]) {
                is EditStatus.Refused -> Text(s.reason, color = MaterialTheme.colorScheme.error, style = MaterialTheme.typography.bodySmall)
                is EditStatus.Pending -> Text("pending", style = MaterialTheme.typography.bodySmall)
                is EditStatus.NotConfirmed -> Text("not confirmed: ${s.reason}", color = Color(0xFFE65100), style = MaterialTheme.typography.bodySmall)
                else -> {}
            }
        }
    }
}
