package org.pocketbot.desktop.ui

import androidx.compose.foundation.background
import androidx.compose.foundation.clickable
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.Spacer
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.size
import androidx.compose.foundation.layout.width
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
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.Freshness
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.protocol.LineFlags

private val columns = listOf("robot" to 160, "battery" to 80, "mode" to 110, "speed" to 110, "line" to 130, "track" to 190, "link" to 280)

/** Every connected robot side by side, one row each: for fleets. A click selects a robot. */
@Composable
fun OverviewView(model: PanelModel) {
    val robots by model.robots.collectAsState()
    val selected by model.selected.collectAsState()
    Column(Modifier.verticalScroll(rememberScrollState())) {
        Text("Fleet overview: ${robots.size} robot(s)", style = MaterialTheme.typography.titleLarge)
        Row(Modifier.padding(vertical = 8.dp)) {
            for ((title, width) in columns) Text(title, Modifier.width(width.dp), style = MaterialTheme.typography.labelLarge)
        }
        HorizontalDivider()
        for (r in robots) {
            OverviewRow(r, r == selected) { model.select(r) }
            HorizontalDivider()
        }
    }
}

@Composable
private fun OverviewRow(robot: RobotModel, selected: Boolean, onClick: () -> Unit) {
    val s by robot.robot.state.collectAsState()
    val connection by robot.robot.connection.collectAsState()
    val stats by robot.robot.linkStats.collectAsState()
    val freshness by robot.freshness.collectAsState()
    val bg = if (selected) MaterialTheme.colorScheme.primaryContainer else MaterialTheme.colorScheme.surface
    Row(Modifier.fillMaxWidth().background(bg).clickable(onClick = onClick).padding(vertical = 6.dp).testTag("overview-${robot.name}"),
        verticalAlignment = Alignment.CenterVertically) {
        val line = s.line
        val cells = listOf(
            robot.name,
            "%.2f V".format(s.power.batteryMv / 1000.0),
            s.locomotion.mode.name.lowercase(),
            "%.2f m/s".format((s.wheels.speedLeftMmps + s.wheels.speedRightMmps) / 2000.0),
            if (line.flags and LineFlags.SEEN != 0) "${line.position} ‰" else "no line",
        )
        // Battery and mode come with full states only; speed and line with reduced ones too.
        val stale = listOf(false, freshness != Freshness.ALL, freshness != Freshness.ALL, freshness == Freshness.NONE, freshness == Freshness.NONE)
        cells.forEachIndexed { i, text ->
            Text(text, Modifier.width(columns[i].second.dp).stale(stale[i]), style = MaterialTheme.typography.bodyMedium, color = valueColour(stale[i]))
        }
        TrackCell(robot, Modifier.width(columns[cells.size].second.dp), stale = freshness != Freshness.ALL)
        Row(Modifier.width(columns.last().second.dp), verticalAlignment = Alignment.CenterVertically) {
            Spacer(Modifier.size(8.dp).background(connectionColour(connection), CircleShape))
            Text(" ${describe(connection)} · ${stats.framesReceived} frames · ${stats.reconnects} reconnects", style = MaterialTheme.typography.bodySmall)
        }
    }
}

/**
 * The track behaviour (thesis A.3) in one cell: its status, the orange light while the robot holds the token, and how
 * often the token came to it (once the token is or was here).
 */
@Composable
private fun TrackCell(robot: RobotModel, modifier: Modifier, stale: Boolean) {
    val track by robot.robot.track.state.collectAsState()
    val holds = track.token != 0
    Row(modifier, verticalAlignment = Alignment.CenterVertically) {
        if (holds) TokenLight(true, Modifier.padding(end = 6.dp).testTag("overview-token-${robot.name}"))
        val visits = if (holds || track.tokenVisits > 0) " · ${track.tokenVisits} visits" else ""
        Text(track.status.name.lowercase().replace('_', ' ') + visits, Modifier.testTag("overview-track-${robot.name}").stale(stale), style = MaterialTheme.typography.bodyMedium, color = valueColour(stale))
    }
}
