package org.pocketbot.desktop.ui

import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.lazy.LazyColumn
import androidx.compose.foundation.lazy.items
import androidx.compose.foundation.lazy.rememberLazyListState
import androidx.compose.material3.FilterChip
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.Text
import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.text.font.FontFamily
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.RobotModel

private val levels = listOf(1 to "errors", 2 to "info", 3 to "verbose", 4 to "trace")

/**
 * The robot's debug text (and the SDK's link messages), filtered by level, a message repeated in a row shown once with
 * its count; and the robot's own debug level.
 */
@Composable
fun ConsoleView(robot: RobotModel) {
    val messages by robot.console.collectAsState()
    val values by robot.robot.settings.values.collectAsState()
    val robotLevel = remember(values) { robot.robot.settings.debug.level.value }
    var shown by remember { mutableStateOf(4) }
    val visible = messages.filter { it.message.level <= shown }
    val list = rememberLazyListState()
    LaunchedEffect(visible.size) { if (visible.isNotEmpty()) list.scrollToItem(visible.size - 1) }
    Column(verticalArrangement = Arrangement.spacedBy(8.dp)) {
        Row(horizontalArrangement = Arrangement.spacedBy(6.dp), verticalAlignment = Alignment.CenterVertically) {
            Text("${robot.name}: console", style = MaterialTheme.typography.titleLarge, modifier = Modifier.weight(1f))
            Text("show up to", style = MaterialTheme.typography.bodySmall)
            for ((l, name) in levels) FilterChip(shown == l, { shown = l }, { Text(name) }, Modifier.testTag("show-level-$l"))
            OutlinedButton(onClick = { robot.clearConsole() }) { Text("Clear") }
        }
        Row(horizontalArrangement = Arrangement.spacedBy(6.dp), verticalAlignment = Alignment.CenterVertically) {
            Text("robot's debug level: $robotLevel", Modifier.testTag("robot-debug-level"), style = MaterialTheme.typography.bodySmall)
            for ((l, name) in levels) FilterChip(robotLevel == l, { robot.setDebugLevel(l) }, { Text("set $name") }, Modifier.testTag("set-level-$l"))
        }
        LazyColumn(Modifier.fillMaxWidth().weight(1f).testTag("console"), state = list) {
            items(visible) { line ->
                Text(line.text(), Modifier.testTag("console-line"), fontFamily = FontFamily.Monospace, style = MaterialTheme.typography.bodySmall,
                    color = if (line.message.level <= 1) MaterialTheme.colorScheme.error else MaterialTheme.colorScheme.onSurface)
            }
        }
    }
}
