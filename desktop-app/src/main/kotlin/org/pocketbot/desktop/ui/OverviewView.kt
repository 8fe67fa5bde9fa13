package org.pocketbot.desktop.ui

import androidx.compose.foundation.background
import androidx.compose.foundation.clickable
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.Spacer
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.size
import androidx.compose.foundation.layout.width
import androidx.compose.foundation.horizontalScroll
import androidx.compose.foundation.rememberScrollState
import androidx.compose.foundation.shape.CircleShape
import androidx.compose.foundation.verticalScroll
import androidx.compose.material3.HorizontalDivider
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.graphicsLayer
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.text.style.TextOverflow
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.sdk.LineFlag
import org.pocketbot.sdk.StateFreshness

private val columns = listOf("robot" to 160, "battery" to 80, "mode" to 110, "speed" to 110, "line" to 130, "track" to 190, "link" to 280)
private val tableWidth = columns.sumOf { it.second }.dp
private fun width(column: String) = columns.first { it.first == column }.second.dp

/** Every connected robot side by side, one row each: for fleets. A click selects a robot. */
@Composable
fun OverviewView(model: PanelModel) {
    val robots by model.robots.collectAsState()
    val selected by model.selected.collectAsState()
    // A window narrower than the table scrolls it sideways: its rows stay one line each.
    Column(Modifier.verticalScroll(rememberScrollState()).horizontalScroll(rememberScrollState())) {
        Text("Fleet overview: ${robots.size} robot(s)", style = MaterialTheme.typography.titleLarge)
        Row(Modifier.padding(vertical = 8.dp)) {
            for ((title, width) in columns) Text(title, Modifier.width(width.dp), style = MaterialTheme.typography.labelLarge)
        }
        HorizontalDivider(Modifier.width(tableWidth))
        for (r in robots) {
            OverviewRow(r, r == selected) { model.select(r) }
            HorizontalDivider(Modifier.width(tableWidth))
        }
    }
}

@Composable
private fun OverviewRow(robot: RobotModel, selected: Boolean, onClick: () -> Unit) {
    val freshness by robot.freshness.collectAsState()
    // Its own layer, and a background only when selected (the surface shows through otherwise): its values change a
    // few times a second, and then this row alone is drawn again.
    val bg = if (selected) MaterialTheme.colorScheme.primaryContainer else Color.Transparent
    Row(Modifier.width(tableWidth).graphicsLayer().background(bg).clickable(onClick = onClick).padding(vertical = 6.dp).testTag("overview-${robot.name}"),
        verticalAlignment = Alignment.CenterVertically) {
        StateCells(robot, freshness)
        TrackCell(robot, Modifier.width(width("track")), stale = !freshness.full.isLive)
        LinkCell(robot, freshness, Modifier.width(width("link")))
    }
}

/**
 * The cells from the robot's state: composed again as the state changes (a few times a second), apart from the row.
 * Battery and mode come with full states only; speed and line with reduced ones too: each is greyed when not live.
 */
@Composable
private fun StateCells(robot: RobotModel, freshness: StateFreshness) {
    val s by robot.robot.state.collectAtHumanRate()
    val line = s.line
    val full = !freshness.full.isLive
    val reduced = !freshness.reduced.isLive
    Text(robot.name, Modifier.width(width("robot")), style = MaterialTheme.typography.bodyMedium, maxLines = 1, overflow = TextOverflow.Ellipsis)
    StateCell(robot, "battery", decimals(s.power.batteryMv / 1000.0, 2) + " V", full)
    StateCell(robot, "mode", s.locomotion.mode.name.lowercase(), full)
    StateCell(robot, "speed", decimals((s.wheels.speedLeftMmps + s.wheels.speedRightMmps) / 2000.0, 2) + " m/s", reduced)
    StateCell(robot, "line", if (LineFlag.SEEN in line.flags) "${line.position} ‰" else "no line", reduced)
}

@Composable
private fun StateCell(robot: RobotModel, column: String, text: String, stale: Boolean) {
    Text(text, Modifier.width(width(column)).testTag("overview-$column-${robot.name}").stale(stale), style = MaterialTheme.typography.bodyMedium,
        color = valueColour(stale), maxLines = 1, overflow = TextOverflow.Ellipsis)
}

/** The link's state and counters; while the values are not live, how old they are. */
@Composable
private fun LinkCell(robot: RobotModel, freshness: StateFreshness, modifier: Modifier) {
    val connection by robot.robot.connection.collectAsState()
    val trouble by robot.linkTrouble.collectAsState()
    val stats by robot.robot.linkStats.collectAtHumanRate()
    Row(modifier, verticalAlignment = Alignment.CenterVertically) {
        Spacer(Modifier.size(8.dp).background(connectionColour(connection), CircleShape))
        if (!freshness.reduced.isLive) {
            Text(" values ${asOf(freshness.reduced).removePrefix("as of ")} ·", Modifier.testTag("overview-age-${robot.name}"),
                style = MaterialTheme.typography.bodySmall, color = MaterialTheme.colorScheme.error, maxLines = 1)
        }
        Text(" ${describe(connection, trouble)} · ${stats.framesReceived} frames · ${stats.reconnects} reconnects", style = MaterialTheme.typography.bodySmall,
            maxLines = 1, overflow = TextOverflow.Ellipsis)
    }
}

/**
 * The track behaviour (thesis A.3) in one cell: its status, the orange light while the robot holds the token, and how
 * often the token came to it (once the token is or was here).
 */
@Composable
private fun TrackCell(robot: RobotModel, modifier: Modifier, stale: Boolean) {
    val track by robot.robot.track.state.collectAtHumanRate()
    val holds = track.token != 0
    Row(modifier, verticalAlignment = Alignment.CenterVertically) {
        if (holds) TokenLight(true, Modifier.padding(end = 6.dp).testTag("overview-token-${robot.name}"))
        val visits = if (holds || track.tokenVisits > 0) " · " + visitsText(track.tokenVisits) else ""
        Text(track.status.name.lowercase().replace('_', ' ') + visits, Modifier.testTag("overview-track-${robot.name}").stale(stale),
            style = MaterialTheme.typography.bodyMedium, color = valueColour(stale), maxLines = 1, overflow = TextOverflow.Ellipsis)
    }
}
