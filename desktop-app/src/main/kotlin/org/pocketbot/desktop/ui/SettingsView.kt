package org.pocketbot.desktop.ui

import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.ExperimentalLayoutApi
import androidx.compose.foundation.layout.FlowRow
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.width
import androidx.compose.foundation.lazy.LazyColumn
import androidx.compose.foundation.lazy.items
import androidx.compose.foundation.text.KeyboardActions
import androidx.compose.foundation.text.KeyboardOptions
import androidx.compose.material3.FilterChip
import androidx.compose.material3.HorizontalDivider
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.OutlinedButton
import androidx.compose.material3.OutlinedTextField
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.runtime.Composable
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.runtime.key
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.runtime.setValue
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.text.input.ImeAction
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.EditStatus
import org.pocketbot.desktop.model.RobotModel
import org.pocketbot.sdk.ConnectionState
import org.pocketbot.sdk.EnumSetting
import org.pocketbot.sdk.SettingField

/** The whole settings tree, grouped by module, with units, ranges and docs; each edit writes that field only. */
@OptIn(ExperimentalLayoutApi::class)
@Composable
fun SettingsView(robot: RobotModel) {
    val values by robot.robot.settings.values.collectAsState() // recompose on every confirmed change
    val edits by robot.edits.collectAsState()
    val reloads by robot.reloads.collectAsState()
    val connection by robot.robot.connection.collectAsState()
    val groups = remember(robot) { robot.robot.settings.fields.groupBy { it.name.substringBefore('.') } }
    Column {
        Text("${robot.name}: settings", style = MaterialTheme.typography.titleLarge)
        // Wraps in a narrow window rather than squeezing the title or the list.
        FlowRow(Modifier.padding(top = 4.dp), horizontalArrangement = Arrangement.spacedBy(8.dp), verticalArrangement = Arrangement.spacedBy(4.dp)) {
            OutlinedButton(onClick = { robot.readAllSettings() }, Modifier.testTag("settings-read")) { Text("Read all") }
            OutlinedButton(onClick = { robot.saveSettings() }, Modifier.testTag("settings-save")) { Text("Save to EEPROM") }
            OutlinedButton(onClick = { robot.loadDefaults() }, Modifier.testTag("settings-defaults")) { Text("Load defaults") }
            OutlinedButton(onClick = { chooseFile("Export settings", save = true, "${robot.name}-settings.json")?.let(robot::exportSettings) }) { Text("Export JSON") }
            OutlinedButton(onClick = { chooseFile("Import settings", save = false)?.let(robot::importSettings) }) { Text("Import JSON") }
        }
        LazyColumn(Modifier.fillMaxWidth().padding(top = 8.dp).testTag("settings-list")) {
            for ((group, fields) in groups) {
                item(key = "group-$group") {
                    Text(group, style = MaterialTheme.typography.titleMedium, color = MaterialTheme.colorScheme.primary,
                        modifier = Modifier.padding(top = 12.dp, bottom = 4.dp))
                    HorizontalDivider()
                }
                items(fields, key = { it.name }) { field ->
                    key(values, reloads) { SettingRow(field, edits[field.name], connection) { text -> robot.write(field.name, text) } }
                }
            }
        }
    }
}

/**
 * One setting: its name and what it does, its value (typed, or an enumeration's names to click), the edit's status
 * under it, unit and range. The value keeps its width in a narrow window; the description gives way.
 */
@Composable
private fun SettingRow(field: SettingField<*>, status: EditStatus?, connection: ConnectionState, onWrite: (String) -> Unit) {
    val current = field.valueText
    var text by remember(field.name, current) { mutableStateOf(current) }
    Row(Modifier.fillMaxWidth().padding(vertical = 2.dp), verticalAlignment = Alignment.CenterVertically) {
        Column(Modifier.weight(1f).padding(end = 8.dp)) {
            Text(field.name.substringAfter('.'), style = MaterialTheme.typography.bodyMedium)
            Text(field.doc, style = MaterialTheme.typography.bodySmall, color = MaterialTheme.colorScheme.onSurfaceVariant, maxLines = 2)
        }
        Column(Modifier.width(280.dp)) {
            if (field is EnumSetting<*>) {
                // An enumeration is chosen by name, written as it is clicked.
                Row(horizontalArrangement = Arrangement.spacedBy(6.dp)) {
                    for (name in field.names) {
                        FilterChip(name == current, { onWrite(name) }, { Text(name) }, Modifier.testTag("setting-${field.name}-$name"))
                    }
                }
            } else {
                Row(verticalAlignment = Alignment.CenterVertically) {
                    OutlinedTextField(text, { text = it }, Modifier.width(210.dp).testTag("setting-${field.name}"), singleLine = true,
                        keyboardOptions = KeyboardOptions(imeAction = ImeAction.Done), keyboardActions = KeyboardActions(onDone = { onWrite(text) }))
                    TextButton(onClick = { onWrite(text) }, enabled = text != current || status is EditStatus.Refused || status is EditStatus.NotConfirmed,
                        modifier = Modifier.testTag("write-${field.name}")) { Text("Write") }
                }
            }
            if (status != null) {
                Text(describe(status, connection), Modifier.testTag("status-${field.name}"), style = MaterialTheme.typography.bodySmall,
                    color = when (status) {
                        is EditStatus.Refused -> MaterialTheme.colorScheme.error
                        is EditStatus.NotConfirmed -> Color(0xFFE65100)
                        is EditStatus.Acknowledged -> Color(0xFF2E7D32)
                        else -> Color.Gray
                    })
            }
        }
        Column(Modifier.width(150.dp).padding(start = 8.dp)) {
            Text(field.unit.ifEmpty { "-" }, style = MaterialTheme.typography.bodySmall)
            Text(field.rangeText, Modifier.testTag("range-${field.name}"), style = MaterialTheme.typography.bodySmall,
                color = MaterialTheme.colorScheme.onSurfaceVariant)
        }
    }
}

/**
 * An edit's status as the settings view shows it. The robot's refusal and a link that failed before the robot
 * answered read differently: the first is the robot's word, the second says nothing about what the robot holds.
 */
fun describe(s: EditStatus?, connection: ConnectionState = ConnectionState.Connected): String = when (s) {
    null -> ""
    is EditStatus.Pending -> "pending: ${s.text}" + if (connection != ConnectionState.Connected) " (link ${describe(connection)}; sent when it is back)" else ""
    is EditStatus.Acknowledged -> "acknowledged: ${s.text}"
    is EditStatus.Refused -> "refused: ${s.reason}"
    is EditStatus.NotConfirmed -> "not confirmed: ${s.reason}"
}

/** A native file dialog; null when cancelled or when there is no display. */
fun chooseFile(title: String, save: Boolean, suggested: String? = null): java.io.File? {
    if (java.awt.GraphicsEnvironment.isHeadless()) return null
    val dialog = java.awt.FileDialog(null as java.awt.Frame?, title, if (save) java.awt.FileDialog.SAVE else java.awt.FileDialog.LOAD)
    suggested?.let { dialog.file = it }
    dialog.isVisible = true
    val name = dialog.file ?: return null
    return java.io.File(dialog.directory, name)
}
