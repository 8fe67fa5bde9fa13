package org.pocketbot.desktop.ui

import androidx.compose.foundation.Canvas
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.geometry.Size
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.Path
import androidx.compose.ui.graphics.StrokeCap
import androidx.compose.ui.graphics.StrokeJoin
import androidx.compose.ui.graphics.drawscope.DrawScope
import androidx.compose.ui.graphics.drawscope.Stroke
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.text.TextStyle
import androidx.compose.ui.text.drawText
import androidx.compose.ui.unit.dp
import androidx.compose.ui.unit.sp
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.desktop.model.WorldSnapshot
import org.pocketbot.sdk.TrajectoryPoint

/** Every connected robot's odometry path (a thin line) and, for emulated robots, the true path (a wide pale band), on the world. */
@Composable
fun TrajectoryView(model: PanelModel) {
    val robots by model.robots.collectAsState()
    val selected by model.selected.collectAsState()
    val world = model.emulator?.world?.collectAsState()?.value
    val odometry = robots.map { it.robot.odometry.trajectory.points.collectAsState().value }
    Column(verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            Text("Trajectories", style = MaterialTheme.typography.titleLarge, modifier = Modifier.weight(1f))
            Text(robots.zip(odometry).joinToString(" · ") { (r, points) -> "${r.name} %.2f m".format(lengthOf(points)) },
                Modifier.testTag("trajectory-lengths"), style = MaterialTheme.typography.bodySmall)
            OutlinedButton(onClick = { robots.forEach { it.robot.odometry.clearTrajectory() }; model.emulator?.clearPaths() },
                Modifier.testTag("trajectory-clear")) { Text("Clear") }
            OutlinedButton(onClick = {
                val r = selected ?: return@OutlinedButton
                chooseFile("Export ${r.name}'s path as CSV", true, "${r.name}-trajectory.csv")?.writeText(model.trajectoryCsv(r))
            }, enabled = selected != null) { Text("Export CSV") }
            OutlinedButton(onClick = {
                chooseFile("Export trajectories as PNG", true, "trajectories.png")?.let { f -> exportPng(f, 1000, 800) { drawPaths(robots, odometry, world) } }
            }) { Text("Export PNG") }
        }
        Canvas(Modifier.weight(1f).fillMaxWidth().testTag("trajectory-canvas")) { drawPaths(robots, odometry, world) }
    }
}

/** The [odometry] paths of [robots] and their true paths on [world] (or fitted to the paths when there is no world). */
fun DrawScope.drawPaths(robots: List<RobotModel>, odometry: List<List<TrajectoryPoint>>, world: WorldSnapshot?) {
    val truth = robots.map { r -> world?.robots?.firstOrNull { it.address == r.address }?.path?.points?.value ?: emptyList() }
    val all = (odometry + truth).flatten()
    val frame = if (world != null) WorldFrame(0.0, 0.0, world.world.widthM, world.world.heightM, size)
    else WorldFrame((all.minOfOrNull { it.pose.xM } ?: -0.5) - 0.1, (all.minOfOrNull { it.pose.yM } ?: -0.5) - 0.1,
        (all.maxOfOrNull { it.pose.xM } ?: 0.5) + 0.1, (all.maxOfOrNull { it.pose.yM } ?: 0.5) + 0.1, size)
    if (world != null) drawWorld(world.world, frame, world.boxes)
    // The true path underneath as a wide pale band, the odometry on top as a thin line: where they part, odometry drifts.
    robots.forEachIndexed { i, _ ->
        drawPath(pathOf(truth[i], frame), robotColours[i % robotColours.size].copy(alpha = 0.28f), style = Stroke(TRUE_WIDTH, cap = StrokeCap.Round, join = StrokeJoin.Round))
    }
    robots.forEachIndexed { i, r ->
        val colour = robotColours[i % robotColours.size]
        drawPath(pathOf(odometry[i], frame), colour, style = Stroke(2f))
        drawRobot(r.robot.odometry.pose.value, frame, colour, filled = false)
    }
    drawLegend(robots.map { it.name }, truth.any { it.isNotEmpty() })
}

private const val TRUE_WIDTH = 12f

/** Which colour is which robot, and which line is odometry and which the true path: also in an exported PNG. */
private fun DrawScope.drawLegend(names: List<String>, withTruth: Boolean) {
    if (names.isEmpty()) return
    val style = TextStyle(fontSize = 12.sp, color = Color.DarkGray)
    val rows = names.size + if (withTruth) 2 else 1
    drawRect(Color.White.copy(alpha = 0.85f), Offset(8f, 8f), Size(230f, 20f * rows + 10f))
    var y = 18f
    fun row(text: String, draw: DrawScope.(Offset) -> Unit) {
        draw(Offset(18f, y + 8f))
        drawText(offscreenTextMeasurer, text, Offset(62f, y), style)
        y += 20f
    }
    row("odometry (thin line)") { drawLine(Color.DarkGray, it, it + Offset(34f, 0f), 2f) }
    if (withTruth) row("true path (wide band)") { drawLine(Color.DarkGray.copy(alpha = 0.28f), it, it + Offset(34f, 0f), TRUE_WIDTH, StrokeCap.Round) }
    names.forEachIndexed { i, n -> row(n) { drawLine(robotColours[i % robotColours.size], it, it + Offset(34f, 0f), 4f) } }
}

/** Length of the path through [points], in metres. */
fun lengthOf(points: List<TrajectoryPoint>): Double = points.zipWithNext { a, b -> a.pose.distanceTo(b.pose) }.sum()

private fun pathOf(points: List<TrajectoryPoint>, frame: WorldFrame): Path = Path().apply {
    points.forEachIndexed { i, p -> frame.at(p.pose.xM, p.pose.yM).let { if (i == 0) moveTo(it.x, it.y) else lineTo(it.x, it.y) } }
}
