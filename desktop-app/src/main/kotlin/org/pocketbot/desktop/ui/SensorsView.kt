package org.pocketbot.desktop.ui

import androidx.compose.foundation.Canvas
import androidx.compose.foundation.background
import androidx.compose.foundation.border
import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Box
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.ColumnScope
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.height
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.size
import androidx.compose.foundation.layout.width
import androidx.compose.foundation.rememberScrollState
import androidx.compose.foundation.verticalScroll
import androidx.compose.material3.CardDefaults
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.ui.Modifier
import androidx.compose.ui.geometry.Offset
import androidx.compose.ui.geometry.Size
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.semantics.contentDescription
import androidx.compose.ui.semantics.semantics
import androidx.compose.ui.text.font.FontStyle
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.sdk.Colour
import org.pocketbot.sdk.LineFlag
import org.pocketbot.sdk.RobotState
import org.pocketbot.sdk.hearsRobot
import org.pocketbot.sdk.seesObstacle

/** Every sensor and status of the selected robot, live. */
@Composable
fun SensorsView(robot: RobotModel) {
    val s by robot.robot.state.collectAsState()
    val stats by robot.robot.linkStats.collectAsState()
    val freshness by robot.freshness.collectAsState()
    // What reduced states carry stays live while tuning; the rest is greyed: it dates from the last full state. A lost
    // link greys everything.
    val old = !freshness.full.isLive
    val all = !freshness.reduced.isLive
    Column(Modifier.verticalScroll(rememberScrollState()), verticalArrangement = Arrangement.spacedBy(12.dp)) {
        Text("${robot.name}: sensors", style = MaterialTheme.typography.titleLarge)
        StaleBanner(freshness)
        Panel("Line sensor") { LineBars(s.line, rawStale = old, positionStale = all) }
        Row(horizontalArrangement = Arrangement.spacedBy(12.dp)) {
            Panel("Wheels", Modifier.weight(1f)) {
                Value("encoders", "${s.encoders.left} / ${s.encoders.right} pulses", Modifier.testTag("wheels-encoders"), stale = all)
                Value("speed", "${s.wheels.speedLeftMmps} / ${s.wheels.speedRightMmps} mm/s", Modifier.testTag("wheels-speed"), stale = all)
                Value("PWM", "${decimals(s.wheels.pwmLeft / 10.0, 1)} / ${decimals(s.wheels.pwmRight / 10.0, 1)} %", Modifier.testTag("wheels-pwm"), stale = old)
            }
            Panel("IR proximity", Modifier.weight(1f)) {
                Value("front", describe(s.proximity.front), Modifier.testTag("ir-front"), stale = old)
                Value("rear", describe(s.proximity.rear), Modifier.testTag("ir-rear"), stale = old)
            }
            Panel("Colour", Modifier.weight(1f)) {
                Row(horizontalArrangement = Arrangement.spacedBy(8.dp)) {
                    Box(Modifier.size(36.dp).background(Color(s.colour.red, s.colour.green, s.colour.blue), MaterialTheme.shapes.small)
                        .border(1.dp, Color.Gray, MaterialTheme.shapes.small))
                    Column {
                        Text(s.colour.detected.name.lowercase(), Modifier.testTag("colour-class").stale(old), style = MaterialTheme.typography.bodyLarge,
                            color = valueColour(old))
                        Text("r ${s.colour.red} g ${s.colour.green} b ${s.colour.blue} c ${s.colour.clear}", style = MaterialTheme.typography.bodySmall,
                            color = valueColour(old))
                    }
                }
            }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(12.dp)) {
            Panel("Accelerometer", Modifier.weight(1f)) {
                Value("x / y / z", "${s.accel.xMg} / ${s.accel.yMg} / ${s.accel.zMg} mg", stale = old)
            }
            Panel("Power", Modifier.weight(1f)) {
                Value("battery", "%.2f V".format(s.power.batteryMv / 1000.0), Modifier.testTag("battery"), stale = old)
                Value("current", "${s.power.currentMa} mA", stale = old)
                Value("MCU", "%.1f °C".format(s.power.mcuTempDc / 10.0), stale = old)
            }
            Panel("Locomotion", Modifier.weight(1f)) {
                Value("mode", s.locomotion.mode.name.lowercase(), Modifier.testTag("loco-mode"), stale = old)
                // Movement id 0 is none: the robot numbers movements from 1.
                val running = if (s.locomotion.currentId == 0) "none running" else "running #${s.locomotion.currentId}"
                val finished = if (s.locomotion.finishedId == 0) "none finished" else "last finished #${s.locomotion.finishedId}"
                Value("queue", "${s.locomotion.queueLength} ($running, $finished)",
                    Modifier.testTag("loco-queue"), stale = old)
                Value("line follower", "${s.lineFollow.status.name.lowercase()} on ${s.lineFollow.segment.name.lowercase()}", stale = old)
            }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(12.dp)) {
            Panel("Firmware", Modifier.weight(1f)) {
                Value("robot time", "%.1f s".format(s.time.timeMs / 1000.0), Modifier.testTag("robot-time"), stale = all)
                Value("tick max", "${s.time.tickMaxUs} µs", stale = old)
                Value("overruns", "${s.time.overruns}" + if (s.time.lastOverrunMs > 0) " (last at ${s.time.lastOverrunMs} ms)" else "", stale = old)
                Value("robot errors", "crc ${s.errors.crc} · framing ${s.errors.framing} · rejected ${s.errors.rejected} · rx overflow ${s.errors.rxOverflow} · tx dropped ${s.errors.txDropped}", stale = old)
            }
            Panel("Link (host side)", Modifier.weight(1f)) {
                Value("frames", "${stats.framesReceived} in (${stats.fullStates} full, ${stats.reducedStates} reduced) · ${stats.framesSent} out")
                Value("dropped", "${stats.dropped} (crc ${stats.badCrc}, framing ${stats.badFraming}, unknown ${stats.unknownType})")
                Value("commands", "retries ${stats.retransmissions} · refused ${stats.refused} · reconnects ${stats.reconnects}")
            }
        }
    }
}

/**
 * The eight spots as bars (darker tape = taller) with the line position marker under them. [rawStale]: the spots date
 * from the last full state (reduced states carry only the position), drawn greyed; [positionStale] likewise.
 */
@Composable
fun LineBars(line: RobotState.Line, modifier: Modifier = Modifier, rawStale: Boolean = false, positionStale: Boolean = false) {
    val seen = LineFlag.SEEN in line.flags
    val lost = LineFlag.LOST in line.flags
    val bar = if (rawStale) Color.LightGray else MaterialTheme.colorScheme.primary
    Column(modifier) {
        Canvas(Modifier.fillMaxWidth().height(120.dp).semantics { contentDescription = "line spots ${line.raw.joinToString(",")}" }
            .stale(rawStale).testTag("line-bars")) {
            val n = line.raw.size
            val w = size.width / n
            val top = line.raw.maxOrNull()?.coerceAtLeast(1000) ?: 1000
            line.raw.forEachIndexed { i, v ->
                val h = size.height * 0.85f * v / top
                drawRect(Color(0xFFE0E0E0), Offset(i * w + 4, 0f), Size(w - 8, size.height * 0.85f))
                drawRect(bar, Offset(i * w + 4, size.height * 0.85f - h), Size(w - 8, h))
            }
            if (seen) {
                val x = size.width / 2 + line.position / 1000f * size.width / 2
                drawRect(Color(0xFFD32F2F), Offset(x - 3, size.height * 0.88f), Size(6f, size.height * 0.12f))
            }
        }
        Text("position ${line.position} ‰ · " + when { lost -> "line lost"; seen -> "line seen"; else -> "no line" },
            Modifier.testTag("line-status").stale(positionStale), style = MaterialTheme.typography.bodyMedium, color = valueColour(positionStale))
        Text("spots: " + line.raw.joinToString(" "), Modifier.testTag("line-raw").stale(rawStale), style = MaterialTheme.typography.bodySmall,
            color = valueColour(rawStale))
    }
}

fun describe(side: RobotState.ProximitySide): String {
    val parts = mutableListOf<String>()
    if (side.hearsRobot) parts += "robot ${side.robotId}, its ${side.robotLed.name.lowercase()} LED, ${side.distance.name.lowercase()}"
    if (side.seesObstacle) parts += "obstacle"
    return parts.joinToString(" · ").ifEmpty { "clear" }
}

fun colourOf(c: Colour): Color = when (c) {
    Colour.RED -> Color(0xFFC62828)
    Colour.BLUE -> Color(0xFF1565C0)
    Colour.GREEN -> Color(0xFF2E7D32)
    Colour.BLACK -> Color(0xFF212121)
    Colour.WHITE -> Color(0xFFF5F5F5)
    Colour.UNKNOWN -> Color.Gray
}

/**
 * A titled group of controls or values, drawn as a Card looks. Not a Card: that clips its content to its rounded
 * shape, and Skia's software rasterizer builds such an anti-aliased clip again every frame the panel is drawn.
 */
@Composable
fun Panel(title: String, modifier: Modifier = Modifier, content: @Composable ColumnScope.() -> Unit) {
    Column(modifier.background(MaterialTheme.colorScheme.surfaceContainerHighest, CardDefaults.shape).padding(12.dp),
        verticalArrangement = Arrangement.spacedBy(4.dp)) {
        Text(title, style = MaterialTheme.typography.titleSmall, color = MaterialTheme.colorScheme.primary)
        content()
    }
}

/** A labelled value; a [stale] one (from the last full state, not live) is greyed and says so to tests and screen readers. */
@Composable
fun Value(label: String, value: String, valueModifier: Modifier = Modifier, stale: Boolean = false) {
    Row {
        Text(label, Modifier.width(110.dp), style = MaterialTheme.typography.bodySmall, color = MaterialTheme.colorScheme.onSurfaceVariant)
        Text(value, valueModifier.stale(stale), style = MaterialTheme.typography.bodyMedium, color = valueColour(stale),
            fontStyle = if (stale) FontStyle.Italic else null)
    }
}
