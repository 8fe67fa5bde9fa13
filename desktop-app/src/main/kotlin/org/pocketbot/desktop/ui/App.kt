package org.pocketbot.desktop.ui

import androidx.compose.foundation.layout.Arrangement
import androidx.compose.foundation.layout.Box
import androidx.compose.foundation.layout.Column
import androidx.compose.foundation.layout.Row
import androidx.compose.foundation.layout.fillMaxHeight
import androidx.compose.foundation.layout.fillMaxSize
import androidx.compose.foundation.layout.fillMaxWidth
import androidx.compose.foundation.layout.padding
import androidx.compose.foundation.layout.width
import androidx.compose.material3.MaterialTheme
import androidx.compose.material3.PrimaryScrollableTabRow
import androidx.compose.material3.Surface
import androidx.compose.material3.Tab
import androidx.compose.material3.Text
import androidx.compose.material3.TextButton
import androidx.compose.material3.VerticalDivider
import androidx.compose.material3.lightColorScheme
import androidx.compose.runtime.Composable
import androidx.compose.runtime.MutableState
import androidx.compose.runtime.collectAsState
import androidx.compose.runtime.getValue
import androidx.compose.runtime.mutableStateOf
import androidx.compose.runtime.remember
import androidx.compose.ui.Alignment
import androidx.compose.ui.Modifier
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.platform.testTag
import androidx.compose.ui.unit.dp
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.model.RobotModel

/** The panel's main views, as tabs. */
enum class View(val title: String) {
    OVERVIEW("Overview"), WORLD("World"), SENSORS("Sensors"), COMMANDS("Commands"),
    SETTINGS("Settings"), TUNING("PID tuning"), TRAJECTORY("Trajectory"), CONSOLE("Console"),
}

/** The whole panel: robots on the left, the chosen view on the right, messages at the bottom. */
@Composable
fun PanelApp(model: PanelModel, view: MutableState<View> = remember { mutableStateOf(View.OVERVIEW) }) {
    MaterialTheme(colorScheme = lightColorScheme(primary = Color(0xFF1565C0), secondary = Color(0xFF00897B))) {
        Surface(Modifier.fillMaxSize()) {
            Row(Modifier.fillMaxSize()) {
                RobotsSidebar(model, Modifier.width(300.dp).fillMaxHeight())
                VerticalDivider()
                Column(Modifier.fillMaxSize()) {
                    PrimaryScrollableTabRow(selectedTabIndex = view.value.ordinal, edgePadding = 0.dp) {
                        for (v in View.entries) {
                            Tab(selected = view.value == v, onClick = { view.value = v }, text = { Text(v.title) },
                                modifier = Modifier.testTag("tab-${v.name}"))
                        }
                    }
                    val selected by model.selected.collectAsState()
                    selected?.let { WatchingBanner(it) }
                    Box(Modifier.weight(1f).fillMaxWidth().padding(12.dp)) {
                        when (view.value) {
                            View.OVERVIEW -> OverviewView(model)
                            View.WORLD -> WorldView(model)
                            View.TRAJECTORY -> TrajectoryView(model)
                            else -> {
                                val robot = selected
                                if (robot == null) {
                                    Text("Connect a robot (left) to see its ${view.value.title.lowercase()}.",
                                        Modifier.align(Alignment.Center))
                                } else when (view.value) {
                                    View.SENSORS -> SensorsView(robot)
                                    View.COMMANDS -> CommandsView(robot, model)
                                    View.SETTINGS -> SettingsView(robot)
                                    View.TUNING -> TuningView(robot)
                                    View.CONSOLE -> ConsoleView(robot)
                                    else -> {}
                                }
                            }
                        }
                    }
                    Notices(model)
                }
            }
        }
    }
}

/**
 * While another host drives the selected robot: who, that the panel only watches (its commands are refused), and the
 * button that takes the robot over.
 */
@Composable
private fun WatchingBanner(robot: RobotModel) {
    val driving by robot.driving.collectAsState()
    if (driving.byThisHost) return
    Surface(color = MaterialTheme.colorScheme.tertiaryContainer, modifier = Modifier.fillMaxWidth().testTag("watching-banner")) {
        Row(Modifier.padding(horizontal = 12.dp), verticalAlignment = Alignment.CenterVertically) {
            Text("${robot.name}: ${drivingText(driving)}. This panel shows its state and may stop it; its other commands are refused.",
                Modifier.weight(1f), style = MaterialTheme.typography.bodyMedium)
            TextButton(onClick = robot::takeOver, modifier = Modifier.testTag("banner-take-over")) { Text("Take over") }
        }
    }
}

/** The latest messages for the user, each dismissable. */
@Composable
private fun Notices(model: PanelModel) {
    val notices by model.notices.collectAsState()
    if (notices.isEmpty()) return
    Column(Modifier.fillMaxWidth().padding(8.dp), verticalArrangement = Arrangement.spacedBy(4.dp)) {
        for (n in notices) {
            Surface(color = if (n.isError) MaterialTheme.colorScheme.errorContainer else MaterialTheme.colorScheme.secondaryContainer,
                shape = MaterialTheme.shapes.small) {
                Row(Modifier.fillMaxWidth().padding(horizontal = 12.dp), verticalAlignment = Alignment.CenterVertically) {
                    Text(n.text, Modifier.weight(1f).testTag("notice"), style = MaterialTheme.typography.bodyMedium)
                    TextButton(onClick = { model.dismiss(n) }) { Text("Dismiss") }
                }
            }
        }
    }
}
