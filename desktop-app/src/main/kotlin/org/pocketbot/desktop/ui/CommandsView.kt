package org.pocketbot.desktop.ui

import androidx.compose.foundation.Canvas
import androidx.compose.foundation.background
import androidx.compose.foundation.border
import androidx.compose.foundation.focusable
import androidx.compose.foundation.gestures.detectDragGestures
import androidx.compose.foundation.gestures.detectTapGestures
import androidx.compose.foundation.interaction.MutableInteractionSource
import androidx.compose.foundation.interaction.collectIsFocusedAsState
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Box
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.PaddingValues
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.height
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.size
import androidx.compose.foundation.layout.width
import androidx.compose.foundation.rememberScrollState
import androidx.compose.foundation.shape.CircleShape
import androidx.compose.foundation.verticalScroll
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
import androidx.compose.ui.focus.FocusRequester
import androidx.compose.ui.focus.focusRequester
import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.drawscope.Stroke
import androidx.compose.ui.input.key.Key
import androidx.compose.ui.input.key.KeyEventType
import androidx.compose.ui.input.key.key
import androidx.compose.ui.input.key.onKeyEvent
import androidx.compose.ui.input.key.type
import androidx.compose.ui.input.pointer.pointerInput
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.EditStatus
import org.pocketbot.desktop.model.MovementDraft
import org.pocketbot.desktop.model.MovementKind
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.RobotModel
import kotlinx.coroutines.flow.update
import org.pocketbot.sdk.ColourMode
import org.pocketbot.sdk.LocoMode
import org.pocketbot.sdk.Movement
import kotlin.math.hypot
import kotlin.math.min

/**
 * Movements, their queue and results, stop, teleoperation (keys and joystick), line following, and the track behaviour
 * of this robot or of every robot of [model].
 */
@Composable
fun CommandsView(robot: RobotModel, model: PanelModel) {
    Row(horizontalArrangement = Arrangement.spacedBy(12.dp)) {
        Column(Modifier.weight(1f).verticalScroll(rememberScrollState()), verticalArrangement = Arrangement.spacedBy(12.dp)) {
            Text("${robot.name}: commands", style = MaterialTheme.typography.titleLarge)
            MovementForm(robot, model)
            Panel("Stop", Modifier.fillMaxWidth()) {
                Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                    Button(onClick = { robot.stop(immediate = false) }, Modifier.testTag("stop-braking")) { Text("Stop (braking)") }
                    OutlinedButton(onClick = { robot.stop(immediate = true) }, Modifier.testTag("stop-now")) { Text("Stop now (motors off)") }
                }
            }
            LineFollowing(robot)
            Teleoperation(robot)
        }
        Column(Modifier.weight(1f).verticalScroll(rememberScrollState()), verticalArrangement = Arrangement.spacedBy(12.dp)) {
            TrackBehaviour(robot, model)
            MovementList(robot)
        }
    }
}

/**
 * The movement form. What is typed lives in [PanelModel.movementDraft]: another tab, another robot, a reconnect or a
 * new world keep it. A movement ends line following or the track behaviour: while the robot runs one, the form asks
 * before it enqueues.
 */
@Composable
private fun MovementForm(robot: RobotModel, model: PanelModel) {
    val draft by model.movementDraft.collectAsState()
    val mode by robot.robot.locomotion.state.collectAsState()
    var error by remember { mutableStateOf<String?>(null) }
    var asking by remember(robot) { mutableStateOf<Movement?>(null) }
    fun edit(change: (MovementDraft) -> MovementDraft) = model.movementDraft.update(change)
    Panel("Enqueue a movement", Modifier.fillMaxWidth()) {
        Row(horizontalArrangement = Arrangement.spacedBy(6.dp)) {
            for (k in MovementKind.entries) FilterChip(selected = draft.kind == k, onClick = {
                edit { it.copy(kind = k, amount = if (k == MovementKind.STRAIGHT) "0.10" else if (it.kind == MovementKind.STRAIGHT) "90" else it.amount) }
            }, label = { Text(k.title) }, modifier = Modifier.testTag("kind-${k.name}"))
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            OutlinedTextField(draft.amount, { t -> edit { it.copy(amount = t) } }, Modifier.width(150.dp).testTag("move-amount"), singleLine = true,
                label = { Text(if (draft.kind == MovementKind.STRAIGHT) "distance m" else "angle °") })
            if (draft.kind == MovementKind.ARC) {
                OutlinedTextField(draft.radius, { t -> edit { it.copy(radius = t) } }, Modifier.width(130.dp).testTag("move-radius"), singleLine = true,
                    label = { Text("radius m") })
            }
            OutlinedTextField(draft.speed, { t -> edit { it.copy(speed = t) } }, Modifier.width(130.dp).testTag("move-speed"), singleLine = true,
                label = { Text("speed m/s") })
        }
        val ends = when (mode.mode) {
            LocoMode.LINE_FOLLOW -> "line following"
            LocoMode.TRACK -> "the track behaviour"
            else -> null
        }
        Button(onClick = {
            error = null
            try {
                val m = draft.movement()
                if (ends != null) asking = m else robot.enqueue(m)
            } catch (e: IllegalArgumentException) {
                error = e.message ?: "not a number"
            }
        }, Modifier.testTag("enqueue")) { Text("Enqueue") }
        asking?.let { m ->
            Text("${robot.name} runs ${ends ?: "another command"}: a movement ends ${ends ?: "it"}.", Modifier.testTag("enqueue-warning"),
                color = MaterialTheme.colorScheme.error, style = MaterialTheme.typography.bodyMedium)
            Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                Button(onClick = { asking = null; robot.enqueue(m) }, Modifier.testTag("enqueue-confirm")) { Text("Enqueue, ending ${ends ?: "it"}") }
                OutlinedButton(onClick = { asking = null }, Modifier.testTag("enqueue-cancel")) { Text("Cancel") }
            }
        }
        error?.let { Text(it, color = MaterialTheme.colorScheme.error, modifier = Modifier.testTag("move-error")) }
    }
}

/**
 * The movements queued from this panel, newest first: running (the robot reports it as its current one) or queued
 * until they end, then how. What the robot reports is greyed, with its age, while it is not live.
 */
@Composable
private fun MovementList(robot: RobotModel) {
    val movements by robot.movements.collectAsState()
    val state by robot.robot.locomotion.state.collectAsState()
    val freshness by robot.freshness.collectAsState()
    Panel("Queue and results", Modifier.fillMaxWidth()) {
        // Mode and queue come with full states only.
        val stale = !freshness.full.isLive
        val since = asOf(freshness.full).let { if (it.isEmpty()) "" else " ($it)" }
        // The robot's queue length counts the movement it runs.
        val running = state.mode == LocoMode.MOVEMENT && state.queueLength > 0
        val queue = if (running) "1 running, ${state.queueLength - 1} queued" else "${state.queueLength} queued"
        Text("robot: ${state.mode.name.lowercase()}, $queue$since",
            Modifier.testTag("robot-queue").stale(stale), style = MaterialTheme.typography.bodySmall, color = valueColour(stale))
        if (movements.isEmpty()) Text("Nothing queued from this panel yet.", style = MaterialTheme.typography.bodySmall)
        for (m in movements.asReversed()) {
            val result = m.result
            val open = result == null
            Row(Modifier.fillMaxWidth().testTag("movement-${m.handle.id}")) {
                Text("#${m.handle.id}", Modifier.width(72.dp), style = MaterialTheme.typography.bodySmall)
                Text(m.text, Modifier.weight(1f).padding(end = 12.dp), style = MaterialTheme.typography.bodySmall)
                val status = result?.let { r -> r.outcome.name.lowercase() + (r.done?.let { " (%.3f %s)".format(it, m.handle.movement.unit) } ?: "") }
                    ?: ((if (state.currentId == m.handle.id) "running" else "queued") + since)
                Text(status, Modifier.width(230.dp).testTag("result-${m.handle.id}").stale(open && stale), style = MaterialTheme.typography.bodySmall,
                    color = valueColour(open && stale))
            }
        }
    }
}

@Composable
private fun LineFollowing(robot: RobotModel) {
    var speed by remember { mutableStateOf("0.15") }
    var mode by remember { mutableStateOf(ColourMode.PLAIN) }
    val status by robot.robot.lineFollower.status.collectAsState()
    val freshness by robot.freshness.collectAsState()
    Panel("Line following", Modifier.fillMaxWidth()) {
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            OutlinedTextField(speed, { speed = it }, Modifier.width(130.dp).testTag("follow-speed"), singleLine = true, label = { Text("speed m/s") })
            FilterChip(mode == ColourMode.PLAIN, { mode = ColourMode.PLAIN }, { Text("plain") })
            FilterChip(mode == ColourMode.SEGMENTS, { mode = ColourMode.SEGMENTS }, { Text("colour segments") }, Modifier.testTag("follow-colours"))
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            Button(onClick = { robot.startLineFollowing(speed.trim().toDoubleOrNull(), mode) }, Modifier.testTag("follow-start")) { Text("Start") }
            OutlinedButton(onClick = { robot.stopLineFollowing() }, Modifier.testTag("follow-stop")) { Text("Stop") }
            val stale = !freshness.full.isLive
            Text("${status.status.name.lowercase()} · segment ${status.segment.name.lowercase()}", Modifier.testTag("follow-status").stale(stale),
                color = valueColour(stale))
        }
    }
}

/** The thesis's orange light: the token LED of a robot on the track. */
val tokenColour = Color(0xFFFF8F00)

/** "1 visit", "3 token visits": how often the track token came to a robot. */
fun visitsText(n: Int, of: String = ""): String = "$n ${of}visit" + if (n == 1) "" else "s"

/**
 * Thesis A.3, multiple robots on a track: the behaviour runs in each robot's firmware; the panel starts, reverses and
 * stops it on this robot or on all of them, sets its speed, and shows what this robot reports.
 */
@Composable
private fun TrackBehaviour(robot: RobotModel, model: PanelModel) {
    val track by robot.robot.track.state.collectAsState()
    val edits by robot.edits.collectAsState()
    val connection by robot.robot.connection.collectAsState()
    val freshness by robot.freshness.collectAsState()
    val robots by model.robots.collectAsState()
    var speed by remember(robot) { mutableStateOf(robot.robot.settings.track.speedMps.valueText) }
    Panel("Track behaviour (thesis A.3)", Modifier.fillMaxWidth()) {
        // Compact buttons, a label above each group: the card fits half of a small window.
        val compact = PaddingValues(horizontal = 12.dp)
        Text("this robot", style = MaterialTheme.typography.bodySmall)
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            Button(onClick = { robot.startTrack() }, Modifier.testTag("track-start"), contentPadding = compact) { Text("Start") }
            OutlinedButton(onClick = { robot.reverseTrack() }, Modifier.testTag("track-reverse"), contentPadding = compact) { Text("Reverse") }
            OutlinedButton(onClick = { robot.stopTrack() }, Modifier.testTag("track-stop"), contentPadding = compact) { Text("Stop") }
        }
        Text("all ${robots.size} robots: the behaviour is a fleet's", style = MaterialTheme.typography.bodySmall)
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
            Button(onClick = { model.everyRobot { it.startTrack() } }, Modifier.testTag("track-start-all"), contentPadding = compact) { Text("Start all") }
            OutlinedButton(onClick = { model.everyRobot { it.reverseTrack() } }, Modifier.testTag("track-reverse-all"), contentPadding = compact) { Text("Reverse all") }
            OutlinedButton(onClick = { model.everyRobot { it.stopTrack() } }, Modifier.testTag("track-stop-all"), contentPadding = compact) { Text("Stop all") }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            OutlinedTextField(speed, { speed = it }, Modifier.width(130.dp).testTag("track-speed"), singleLine = true, label = { Text("speed m/s") })
            OutlinedButton(onClick = { robot.setTrackSpeed(speed) }, Modifier.testTag("track-speed-set")) { Text("Set") }
            val status = edits[RobotModel.TRACK_SPEED]
            Text(describe(status, connection), Modifier.testTag("track-speed-status"), style = MaterialTheme.typography.bodySmall,
                color = if (status is EditStatus.Refused) MaterialTheme.colorScheme.error else Color.Unspecified)
        }
        // The track state comes with full states only.
        val stale = !freshness.full.isLive
        Row(horizontalArrangement = Arrangement.spacedBy(8.dp), verticalAlignment = Alignment.CenterVertically) {
            TokenLight(track.token != 0, Modifier.testTag(if (track.token != 0) "track-token" else "track-no-token"))
            val met = if (track.metId == 0) "nobody yet" else robots.firstOrNull { it.robot.identity.robotId == track.metId }?.name ?: "robot ${track.metId}"
            Text("${track.status.name.lowercase().replace('_', ' ')} · " + (if (track.token != 0) "holds the token" else "no token") +
                " · ${visitsText(track.tokenVisits, "token ")} · met $met", Modifier.testTag("track-status").stale(stale),
                style = MaterialTheme.typography.bodyMedium, color = valueColour(stale))
        }
    }
}

/** A round light, orange while the robot holds the token, an empty ring otherwise. */
@Composable
fun TokenLight(on: Boolean, modifier: Modifier = Modifier) {
    Box(modifier.size(14.dp).then(if (on) Modifier.background(tokenColour, CircleShape) else Modifier.border(1.dp, Color.Gray, CircleShape)))
}

/** Arrow keys or WASD while the drive pad has focus; the on-screen joystick with the mouse. */
@Composable
private fun Teleoperation(robot: RobotModel) {
    val maxSpeed = 0.25
    var pressed by remember { mutableStateOf(setOf<Key>()) }
    val focus = remember { FocusRequester() }
    val interaction = remember { MutableInteractionSource() }
    val focused by interaction.collectIsFocusedAsState()
    fun applyKeys(keys: Set<Key>) {
        val fwd = (if (keys.any { it == Key.DirectionUp || it == Key.W }) 1 else 0) - (if (keys.any { it == Key.DirectionDown || it == Key.S }) 1 else 0)
        val turn = (if (keys.any { it == Key.DirectionLeft || it == Key.A }) 1 else 0) - (if (keys.any { it == Key.DirectionRight || it == Key.D }) 1 else 0)
        val v = fwd * maxSpeed * 0.8
        val w = turn * maxSpeed * 0.4
        robot.drive(v - w, v + w)
    }
    Panel("Teleoperation", Modifier.fillMaxWidth()) {
        Row(horizontalArrangement = Arrangement.spacedBy(16.dp), verticalAlignment = Alignment.CenterVertically) {
            Box(Modifier.size(170.dp, 120.dp).border(2.dp, if (focused) MaterialTheme.colorScheme.primary else Color.LightGray, MaterialTheme.shapes.medium)
                .focusRequester(focus).focusable(interactionSource = interaction)
                .pointerInput(Unit) { detectTapGestures(onPress = { focus.requestFocus() }) }
                .onKeyEvent { e ->
                    val driving = e.key in listOf(Key.DirectionUp, Key.DirectionDown, Key.DirectionLeft, Key.DirectionRight, Key.W, Key.A, Key.S, Key.D)
                    if (!driving) return@onKeyEvent false
                    pressed = if (e.type == KeyEventType.KeyDown) pressed + e.key else pressed - e.key
                    applyKeys(pressed)
                    true
                }.testTag("drive-pad"), contentAlignment = Alignment.Center) {
                Text(if (focused) "driving: arrows / WASD" else "click here, then\narrows / WASD", style = MaterialTheme.typography.bodySmall)
            }
            Joystick(maxSpeed) { l, r -> robot.drive(l, r) }
        }
    }
}

/** Drag the knob: up is forward, sideways turns; release stops. Calls [onWheels] with left and right m/s. */
@Composable
private fun Joystick(maxSpeed: Double, onWheels: (Double, Double) -> Unit) {
    var knob by remember { mutableStateOf(Offset.Zero) }
    val colour = MaterialTheme.colorScheme.primary
    Canvas(Modifier.size(120.dp).background(Color(0xFFF0F0F0), CircleShape).testTag("joystick").pointerInput(Unit) {
        val radius = min(size.width, size.height) / 2f
        fun send(o: Offset) {
            val fwd = (-o.y / radius).toDouble()
            val turn = (-o.x / radius).toDouble()
            onWheels((fwd - turn * 0.5) * maxSpeed, (fwd + turn * 0.5) * maxSpeed)
        }
        detectDragGestures(
            onDragStart = { p -> knob = clamp(p - Offset(radius, radius), radius); send(knob) },
            onDragEnd = { knob = Offset.Zero; onWheels(0.0, 0.0) },
            onDragCancel = { knob = Offset.Zero; onWheels(0.0, 0.0) },
        ) { change, _ -> knob = clamp(change.position - Offset(radius, radius), radius); send(knob) }
    }) {
        val r = size.minDimension / 2
        drawCircle(Color.Gray, r - 2, style = Stroke(2f))
        drawCircle(colour, r / 4, center + knob)
    }
}

private fun clamp(o: Offset, radius: Float): Offset {
    val d = hypot(o.x, o.y)
    return if (d <= radius) o else o * (radius / d)
}
