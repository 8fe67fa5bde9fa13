package org.pocketbot.desktop.ui

import androidx.compose.foundation.background
import androidx.compose.foundation.clickable
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.Spacer
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.height
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.size
import androidx.compose.foundation.rememberScrollState
import androidx.compose.foundation.shape.CircleShape
import androidx.compose.foundation.verticalScroll
import androidx.compose.material3.Button
import androidx.compose.material3.Checkbox
import androidx.compose.material3.HorizontalDivider
import androidx.compose.material3.LinearProgressIndicator
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
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
import org.pocketbot.desktop.model.LinkTrouble
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.Driving

/** Finding and connecting robots, and the connected ones with their link, always in view. */
@Composable
fun RobotsSidebar(model: PanelModel, modifier: Modifier = Modifier) {
    val found by model.found.collectAsState()
    val robots by model.robots.collectAsState()
    val scanning by model.scanning.collectAsState()
    val connecting by model.connecting.collectAsState()
    val problems by model.problems.collectAsState()
    val failures by model.connectFailures.collectAsState()
    val selected by model.selected.collectAsState()
    var ticked by remember { mutableStateOf(setOf<String>()) }
    LaunchedEffect(Unit) { if (found.isEmpty()) model.scan() }

    Column(modifier.padding(12.dp).verticalScroll(rememberScrollState()), verticalArrangement = Arrangement.spacedBy(6.dp)) {
        Row(verticalAlignment = Alignment.CenterVertically) {
            Text("Robots found", style = MaterialTheme.typography.titleMedium, modifier = Modifier.weight(1f))
            TextButton(onClick = { model.scan() }, enabled = !scanning, modifier = Modifier.testTag("scan")) { Text(if (scanning) "Scanning" else "Scan") }
        }
        if (scanning) LinearProgressIndicator(Modifier.fillMaxWidth())
        val unconnected = found.filter { f -> robots.none { it.address == f.address } }
        for (f in unconnected) {
            Row(verticalAlignment = Alignment.CenterVertically) {
                Checkbox(checked = f.address in ticked, onCheckedChange = { on -> ticked = if (on) ticked + f.address else ticked - f.address },
                    modifier = Modifier.testTag("tick-${f.address}"))
                Column(Modifier.weight(1f)) {
                    Text(f.name, style = MaterialTheme.typography.bodyMedium)
                    Text("${f.source} · ${f.address}", style = MaterialTheme.typography.bodySmall, color = MaterialTheme.colorScheme.onSurfaceVariant)
                    failures[f.address]?.let { why ->
                        Text(why, Modifier.testTag("connect-failure-${f.address}"), style = MaterialTheme.typography.bodySmall,
                            color = MaterialTheme.colorScheme.error)
                    }
                }
                if (f.address in connecting) Text("connecting", style = MaterialTheme.typography.labelSmall)
            }
        }
        if (unconnected.isEmpty() && !scanning) Text("No robots waiting. Scan looks in the embedded emulator, an emulator's control port, Bluetooth and serial ports.",
            style = MaterialTheme.typography.bodySmall)
        for ((source, why) in problems) Text("$source: $why", style = MaterialTheme.typography.bodySmall, color = MaterialTheme.colorScheme.onSurfaceVariant)
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            Button(onClick = { model.connect(unconnected.filter { it.address in ticked }); ticked = emptySet() },
                enabled = unconnected.any { it.address in ticked }, modifier = Modifier.testTag("connect-ticked")) { Text("Connect") }
            OutlinedButton(onClick = { model.connect(unconnected) }, enabled = unconnected.isNotEmpty(),
                modifier = Modifier.testTag("connect-all")) { Text("Connect all") }
        }
        HorizontalDivider(Modifier.padding(vertical = 6.dp))
        Row(verticalAlignment = Alignment.CenterVertically) {
            Text("Connected", style = MaterialTheme.typography.titleMedium, modifier = Modifier.weight(1f))
            if (robots.size > 1) TextButton(onClick = { robots.forEach(model::disconnect) }, Modifier.testTag("disconnect-all")) { Text("Disconnect all") }
        }
        if (robots.isEmpty()) Text("none yet", style = MaterialTheme.typography.bodySmall)
        for (r in robots) ConnectedRobot(r, r == selected, onSelect = { model.select(r) }, onDisconnect = { model.disconnect(r) })
    }
}

@Composable
private fun ConnectedRobot(robot: RobotModel, selected: Boolean, onSelect: () -> Unit, onDisconnect: () -> Unit) {
    val connection by robot.robot.connection.collectAsState()
    val trouble by robot.linkTrouble.collectAsState()
    val background = if (selected) MaterialTheme.colorScheme.primaryContainer else Color.Transparent
    // Its own layer: its link counters change a few times a second, and the rest of the list need not be drawn again.
    Column(Modifier.fillMaxWidth().graphicsLayer().background(background, MaterialTheme.shapes.small).clickable(onClick = onSelect)
        .padding(8.dp).testTag("robot-${robot.name}")) {
        Row(verticalAlignment = Alignment.CenterVertically) {
            Spacer(Modifier.size(10.dp).background(connectionColour(connection), CircleShape))
            Text(" ${robot.name}", style = MaterialTheme.typography.bodyLarge, modifier = Modifier.weight(1f))
            TextButton(onClick = onDisconnect, modifier = Modifier.height(32.dp).testTag("disconnect-${robot.name}")) { Text("Disconnect") }
        }
        val link = describe(connection, trouble)
        // The address once: a failure's reason often names it already.
        Text(if (robot.address in link) link else "$link · ${robot.address}", Modifier.testTag("robot-link-${robot.name}"),
            style = MaterialTheme.typography.bodySmall)
        Driver(robot, live = connection == ConnectionState.Connected)
        LinkCounters(robot)
    }
}

/**
 * Who drives the robot, and while another host does, the button that takes it over. With the link down the panel
 * cannot know who drives now (the robot frees the drive after its failsafe time): it says who did when last heard.
 */
@Composable
private fun Driver(robot: RobotModel, live: Boolean) {
    val driving by robot.driving.collectAsState()
    Row(verticalAlignment = Alignment.CenterVertically) {
        Text(if (live) drivingText(driving) else drivenWhenLastHeard(driving), Modifier.weight(1f).testTag("driver-${robot.name}"),
            style = MaterialTheme.typography.bodySmall,
            color = if (driving.byThisHost || !live) MaterialTheme.colorScheme.onSurfaceVariant else MaterialTheme.colorScheme.primary)
        if (live && !driving.byThisHost) {
            TextButton(onClick = robot::takeOver, modifier = Modifier.height(32.dp).testTag("take-over-${robot.name}")) { Text("Take over") }
        }
    }
}

/** The panel's words for who drives a robot. */
fun drivingText(d: Driving): String = when {
    d.byThisHost -> "this panel drives it"
    d.driver != null -> "watching: ${d.driver} drives it"
    else -> "watching: no host drives it"
}

/** Who drove a robot when its link was last up: while it is down, the robot may have freed the drive. */
fun drivenWhenLastHeard(d: Driving): String = when {
    d.byThisHost -> "this panel drove it when last heard"
    d.driver != null -> "${d.driver} drove it when last heard"
    else -> "no host drove it when last heard"
}

/** The part of a robot's card that keeps changing, in a scope of its own: the rest is not composed again with it. */
@Composable
private fun LinkCounters(robot: RobotModel) {
    val stats by robot.robot.linkStats.collectAtHumanRate()
    Text("${stats.framesReceived} frames in / ${stats.framesSent} out", style = MaterialTheme.typography.bodySmall,
        color = MaterialTheme.colorScheme.onSurfaceVariant)
    // Losses only when there are some: a healthy link says nothing more, and a troubled one stands out.
    if (stats.dropped > 0 || stats.retransmissions > 0 || stats.reconnects > 0) {
        Text("dropped ${stats.dropped} · retries ${stats.retransmissions} · reconnects ${stats.reconnects}",
            Modifier.testTag("link-losses-${robot.name}"), style = MaterialTheme.typography.bodySmall, color = MaterialTheme.colorScheme.error)
    }
}

fun describe(c: ConnectionState): String = when (c) {
    ConnectionState.Connecting -> "connecting"
    ConnectionState.Connected -> "connected"
    is ConnectionState.Lost -> "lost: ${c.reason}"
    is ConnectionState.Reconnecting -> "reconnecting (attempt ${c.attempt})"
    is ConnectionState.Closed -> "closed" + (c.cause?.message?.let { ": $it" } ?: "")
    else -> c.toString()
}

/**
 * The link in words, a link that stays down summed up (how long, how many attempts, why) instead of retold with every
 * attempt.
 */
@Composable
fun describe(c: ConnectionState, trouble: LinkTrouble?): String {
    if (trouble == null || c is ConnectionState.Closed) return describe(c)
    val seconds = secondsSince(trouble.since) ?: 0
    val attempts = if (trouble.attempts > 0) ", ${trouble.attempts} attempts to reconnect failed" else ""
    return "down for $seconds s$attempts: ${trouble.reason.replace(ATTEMPT, "")}"
}

private val ATTEMPT = Regex("""^reconnect attempt \d+ failed: """)

fun connectionColour(c: ConnectionState): Color = when (c) {
    ConnectionState.Connected -> Color(0xFF2E7D32)
    ConnectionState.Connecting, is ConnectionState.Reconnecting -> Color(0xFFF9A825)
    else -> Color(0xFFC62828)
}
