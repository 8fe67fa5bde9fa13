package org.pocketbot.desktop.ui

import androidx.compose.foundation.Canvas
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.ExperimentalLayoutApi
import androidx.compose.foundation.layout.FlowRow
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.width
import androidx.compose.material3.Button
import androidx.compose.material3.FilterChip
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.OutlinedTextField
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.geometry.Size
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.Path
import androidx.compose.ui.graphics.StrokeCap
import androidx.compose.ui.graphics.drawscope.DrawScope
import androidx.compose.ui.graphics.drawscope.Stroke
import androidx.compose.ui.graphics.drawscope.rotate
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.semantics.contentDescription
import androidx.compose.ui.semantics.semantics
import androidx.compose.ui.text.drawText
import androidx.compose.ui.text.rememberTextMeasurer
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.TrueRobot
import org.pocketbot.emulator.physics.RobotParams
import org.pocketbot.emulator.world.Tape
import org.pocketbot.emulator.world.TapeColour
import org.pocketbot.emulator.world.World
import org.pocketbot.sdk.Pose
import kotlin.math.cos
import kotlin.math.min
import kotlin.math.sin

/**
 * Colours of the robots, by their place in the panel's list (the same in every view). No orange or yellow among them:
 * orange is the track token's light.
 */
val robotColours = listOf(Color(0xFF1565C0), Color(0xFF2E7D32), Color(0xFF6A1B9A), Color(0xFF00838F), Color(0xFFAD1457), Color(0xFF5D4037))

/** The floor, the mark on a robot's front, and the ring round its token light. */
val floorColour = Color(0xFFFAFAF5)
val frontMarkColour = Color.White

/** Maps world metres (y up) to canvas pixels, keeping the aspect ratio. */
class WorldFrame(val xMin: Double, val yMin: Double, val xMax: Double, val yMax: Double, size: Size) {
    private val scale = min(size.width / (xMax - xMin), size.height / (yMax - yMin)).toFloat()
    private val ox = (size.width - scale * (xMax - xMin).toFloat()) / 2
    private val oy = (size.height - scale * (yMax - yMin).toFloat()) / 2
    fun at(x: Double, y: Double) = Offset(ox + ((x - xMin) * scale).toFloat(), size.height - oy - ((y - yMin) * scale).toFloat())
    fun length(m: Double) = (m * scale).toFloat()
    private val size = size
}

fun tapeColour(c: TapeColour): Color = Color(c.r, c.g, c.b)

/** The floor, its tapes (with their colours) and boxes. */
fun DrawScope.drawWorld(world: World, frame: WorldFrame, boxes: List<Pose>) {
    val floorTopLeft = frame.at(0.0, world.heightM)
    val floorBottomRight = frame.at(world.widthM, 0.0)
    drawRect(floorColour, floorTopLeft, Size(floorBottomRight.x - floorTopLeft.x, floorBottomRight.y - floorTopLeft.y))
    for (tape in world.tapes) {
        val stroke = Stroke(width = frame.length(tape.widthM).coerceAtLeast(1.5f), cap = StrokeCap.Round)
        val path = Path()
        when (tape) {
            is Tape.Polyline -> {
                tape.points.forEachIndexed { i, p -> frame.at(p.x, p.y).let { if (i == 0) path.moveTo(it.x, it.y) else path.lineTo(it.x, it.y) } }
                if (tape.closed) path.close()
            }
            is Tape.Arc -> {
                val steps = (kotlin.math.abs(tape.sweepDeg) / 3).toInt().coerceAtLeast(2)
                for (i in 0..steps) {
                    val a = Math.toRadians(tape.startDeg + tape.sweepDeg * i / steps)
                    val p = frame.at(tape.center.x + tape.radiusM * cos(a), tape.center.y + tape.radiusM * sin(a))
                    if (i == 0) path.moveTo(p.x, p.y) else path.lineTo(p.x, p.y)
                }
            }
        }
        drawPath(path, tapeColour(tape.colour), style = stroke)
    }
    world.boxes.forEachIndexed { i, spec ->
        val pose = boxes.getOrNull(i) ?: Pose.ofDegrees(spec.center.x, spec.center.y, spec.angleDeg)
        val c = frame.at(pose.xM, pose.yM)
        rotate(-Math.toDegrees(pose.headingRad).toFloat(), c) {
            val w = frame.length(spec.widthM); val h = frame.length(spec.heightM)
            drawRect(if (spec.movable) Color(0xFFBCAAA4) else Color(0xFF616161), Offset(c.x - w / 2, c.y - h / 2), Size(w, h))
        }
    }
}

/**
 * A PocketBot2 as drawn: its body ([RobotParams] length along the heading, width across), a triangle on its front
 * pointing the way it faces, and the token light in its middle. Points are (forward, left) in metres from the body's
 * centre; [at] turns them into world coordinates for a pose.
 */
object RobotShape {
    private val params = RobotParams()
    val lengthM = params.lengthM
    val widthM = params.widthM
    val body = listOf(lengthM / 2 to widthM / 2, -lengthM / 2 to widthM / 2, -lengthM / 2 to -widthM / 2, lengthM / 2 to -widthM / 2)
    val frontMark = listOf(lengthM / 2 - 0.002 to 0.0, 0.011 to 0.008, 0.011 to -0.008)
    const val LIGHT_RADIUS_M = 0.005

    /** A point well inside the front mark, and one as far behind the centre: only the first is [frontMarkColour]. */
    val insideFrontMark = 0.015 to 0.0
    val insideRear = -0.015 to 0.0

    /** The world coordinates (x, y) of the body point ([forward], [left]) of a robot at [pose]. */
    fun at(pose: Pose, forward: Double, left: Double): Pair<Double, Double> {
        val c = cos(pose.headingRad)
        val s = sin(pose.headingRad)
        return pose.xM + forward * c - left * s to pose.yM + forward * s + left * c
    }
}

/**
 * A robot at [pose]: its body filled in [colour] with a white triangle on its front (the true pose) or, when not
 * [filled], the same shape outlined (the odometry pose); [token] lights its orange light, with a glow round it.
 */
fun DrawScope.drawRobot(pose: Pose, frame: WorldFrame, colour: Color, filled: Boolean, token: Boolean = false) {
    fun path(points: List<Pair<Double, Double>>) = Path().apply {
        points.forEachIndexed { i, (f, l) ->
            val (x, y) = RobotShape.at(pose, f, l)
            frame.at(x, y).let { if (i == 0) moveTo(it.x, it.y) else lineTo(it.x, it.y) }
        }
        close()
    }
    if (!filled) {
        drawPath(path(RobotShape.body), colour, style = Stroke(2f))
        drawPath(path(RobotShape.frontMark), colour, style = Stroke(1.5f))
        return
    }
    drawPath(path(RobotShape.body), colour)
    val c = frame.at(pose.xM, pose.yM)
    val r = frame.length(RobotShape.LIGHT_RADIUS_M).coerceAtLeast(4f)
    if (token) drawCircle(tokenColour.copy(alpha = 0.45f), r * 2.2f, c)
    drawPath(path(RobotShape.frontMark), frontMarkColour)
    if (token) {
        drawCircle(Color.White, r + 1.5f, c)
        drawCircle(tokenColour, r, c)
    }
}

/** The embedded emulator's world, live: tape, boxes, each robot's true pose and its odometry pose; and its controls. */
@OptIn(ExperimentalLayoutApi::class)
@Composable
fun WorldView(model: PanelModel) {
    val emulator = model.emulator
    if (emulator == null) {
        Text("This panel runs without an embedded emulator (started with --no-emulator).")
        return
    }
    val snapshot by emulator.world.collectAsState()
    val robots by model.robots.collectAsState()
    val paused by emulator.paused.collectAsState()
    val speed by emulator.speed.collectAsState()
    var worldName by remember { mutableStateOf(snapshot.world.name) }
    var count by remember { mutableStateOf(snapshot.robots.size.toString()) }
    Column(verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            Text("World ${snapshot.world.name} · t = %.1f s".format(snapshot.timeMs / 1000.0), style = MaterialTheme.typography.titleLarge,
                modifier = Modifier.testTag("world-title"))
            if (paused) Button(onClick = { emulator.resume() }, Modifier.testTag("emu-resume")) { Text("Resume") }
            else OutlinedButton(onClick = { emulator.pause() }, Modifier.testTag("emu-pause")) { Text("Pause") }
            OutlinedButton(onClick = { emulator.singleStep() }, Modifier.testTag("emu-step")) { Text("Step 1 ms") }
            for (f in listOf(0.5, 1.0, 2.0, 5.0)) FilterChip(speed == f, { emulator.setSpeed(f) }, { Text("x$f") }, Modifier.testTag("emu-speed-$f"))
        }
        // Wraps onto a second line where the view is too narrow for every shipped world.
        FlowRow(horizontalArrangement = Arrangement.spacedBy(6.dp), itemVerticalAlignment = Alignment.CenterVertically) {
            for (name in emulator.shippedWorlds) FilterChip(worldName == name, { worldName = name }, { Text(name) }, Modifier.testTag("world-$name"))
            OutlinedButton(onClick = { chooseFile("Open a world file", save = false)?.let { worldName = it.path } }) { Text("World file...") }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            OutlinedTextField(count, { count = it }, Modifier.width(110.dp).testTag("emu-robots"), singleLine = true, label = { Text("robots") })
            Button(onClick = { model.restartEmulator(worldName, count.trim().toIntOrNull() ?: -1) }, Modifier.testTag("emu-restart")) {
                Text("Restart with $worldName".let { if (it.length > 40) "Restart with world file" else it })
            }
            Text("filled: true pose · outline: odometry where it differs · white triangle: front · orange light: track token",
                style = MaterialTheme.typography.bodySmall)
        }
        NetworkRow(model)
        val measurer = rememberTextMeasurer()
        val labelStyle = MaterialTheme.typography.labelSmall.copy(color = MaterialTheme.colorScheme.onSurface)
        /** The panel's name of an emulated robot, or its id when the panel is not connected to it. */
        fun nameOf(t: TrueRobot) = robots.firstOrNull { it.address == t.address }?.name ?: "robot ${t.id}"
        val holders = snapshot.robots.filter { it.holdsToken }.map(::nameOf)
        Canvas(Modifier.weight(1f).fillMaxWidth().testTag("world-canvas").semantics {
            contentDescription = "world ${snapshot.world.name}, ${snapshot.robots.size} robots" +
                if (holders.isEmpty()) "" else "; the track token is with ${holders.joinToString()}"
        }) {
            val w = snapshot.world
            val frame = WorldFrame(0.0, 0.0, w.widthM, w.heightM, size)
            drawWorld(w, frame, snapshot.boxes)
            val drawn = snapshot.robots.map { t -> t to robots.indexOfFirst { it.address == t.address } }
            fun colourOf(t: TrueRobot, index: Int) = robotColours[(if (index >= 0) index else t.id) % robotColours.size]
            // Odometry underneath: where it agrees with the truth the body covers it, where it drifts it shows.
            for ((t, index) in drawn) if (index >= 0) drawRobot(robots[index].robot.odometry.pose.value, frame, colourOf(t, index), filled = false)
            for ((t, index) in drawn) drawRobot(t.pose, frame, colourOf(t, index), filled = true, token = t.holdsToken)
            // Names last, on a pale ground (readable over tape), beside each body whichever way it faces.
            for ((t, index) in drawn) {
                val label = measurer.measure(nameOf(t), labelStyle)
                val c = frame.at(t.pose.xM, t.pose.yM)
                val clear = frame.length(RobotShape.lengthM / 2) + 4f
                val at = Offset(c.x + clear, c.y - clear - label.size.height)
                drawRect(floorColour.copy(alpha = 0.8f), at, Size(label.size.width.toFloat(), label.size.height.toFloat()))
                drawText(label, topLeft = at)
            }
        }
    }
}

/**
 * The embedded emulator on the network: a button that serves it, and while served, the address to type into the phone
 * and which robots another host (a phone, a script) drives now.
 */
@Composable
private fun NetworkRow(model: PanelModel) {
    val emulator = model.emulator ?: return
    val serving by emulator.serving.collectAsState()
    Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
        val served = serving
        if (served == null) {
            OutlinedButton(onClick = { model.serveEmulator() }, Modifier.testTag("emu-serve")) { Text("Serve on the network") }
            Text("so a phone (the PocketBot app) or another computer on this network drives these robots",
                style = MaterialTheme.typography.bodySmall)
        } else {
            OutlinedButton(onClick = { model.stopServingEmulator() }, Modifier.testTag("emu-serve-stop")) { Text("Stop serving") }
            Text("On the network: in the phone app, find the emulator at ${served.addresses.joinToString(" or ")}",
                style = MaterialTheme.typography.bodyMedium, modifier = Modifier.testTag("emu-serving"))
            val robots by model.robots.collectAsState()
            val driven = robots.map { it to it.driving.collectAsState().value }.filter { (_, d) -> !d.byThisHost && d.driver != null }
            if (driven.isNotEmpty()) {
                Text(driven.joinToString(" · ") { (r, d) -> "${r.name} driven by ${d.driver}" },
                    style = MaterialTheme.typography.bodyMedium, color = MaterialTheme.colorScheme.primary,
                    modifier = Modifier.testTag("emu-driven"))
            }
        }
    }
}
