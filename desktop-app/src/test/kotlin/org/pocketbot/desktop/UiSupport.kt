package org.pocketbot.desktop

import androidx.compose.ui.semantics.SemanticsProperties
import androidx.compose.ui.test.ComposeUiTest
import androidx.compose.ui.test.ExperimentalTestApi
import androidx.compose.ui.test.SemanticsNodeInteraction
import androidx.compose.ui.test.hasTestTag
import androidx.compose.ui.test.onNodeWithTag
import androidx.compose.ui.test.performClick
import org.pocketbot.desktop.model.RobotModel

/** How long a loaded CI machine may take: a liveness guard for waits, not a timing assertion. */
const val GUARD_MS = 30_000L

/** The text a node shows: an edit field's text, or its texts joined. */
fun SemanticsNodeInteraction.text(): String {
    val config = fetchSemanticsNode().config
    val editable = if (SemanticsProperties.EditableText in config) config[SemanticsProperties.EditableText] else null
    return editable?.text ?: config.getOrElse(SemanticsProperties.Text) { emptyList() }.joinToString(" ") { it.text }
}

fun SemanticsNodeInteraction.description(): String =
    fetchSemanticsNode().config.getOrElse(SemanticsProperties.ContentDescription) { emptyList() }.joinToString()

/** True when the node says its value dates from the last full state (see ui.stale). */
fun SemanticsNodeInteraction.isStale(): Boolean =
    fetchSemanticsNode().config.getOrElse(SemanticsProperties.StateDescription) { "" } == "stale"

/** True when the node is a selected choice (a chip, a tab, a radio button). */
fun SemanticsNodeInteraction.isSelected(): Boolean = fetchSemanticsNode().config.let { c ->
    c.getOrElse(SemanticsProperties.Selected) { false } ||
        c.getOrElse(SemanticsProperties.ToggleableState) { androidx.compose.ui.state.ToggleableState.Off } == androidx.compose.ui.state.ToggleableState.On
}

@OptIn(ExperimentalTestApi::class)
fun ComposeUiTest.exists(tag: String): Boolean = onAllNodes(hasTestTag(tag)).fetchSemanticsNodes().isNotEmpty()

/**
 * Finds the emulated robot [id] in the sidebar, ticks it and connects it, as a person would; returns it (the first
 * robot connected is the selected one).
 */
@OptIn(ExperimentalTestApi::class)
fun ComposeUiTest.connectRobot(f: PanelFixture, id: Int = 1): RobotModel {
    waitUntil(timeoutMillis = GUARD_MS) { exists("tick-emulator:$id") }
    onNodeWithTag("tick-emulator:$id").performClick()
    onNodeWithTag("connect-ticked").performClick()
    waitUntil(timeoutMillis = GUARD_MS) { exists("robot-PocketBot-$id") && f.panel.selected.value != null }
    return f.panel.robots.value.first { it.name == "PocketBot-$id" }
}

/** [ComposeUiTest.waitUntil] that says what it waited for, and how things stood, when the guard runs out. */
@OptIn(ExperimentalTestApi::class)
fun ComposeUiTest.await(what: String, now: () -> Any? = { null }, condition: () -> Boolean) {
    try {
        waitUntil(timeoutMillis = GUARD_MS, condition = condition)
    } catch (e: androidx.compose.ui.test.ComposeTimeoutException) {
        throw AssertionError("not within $GUARD_MS ms: $what" + (now()?.let { "; now: $it" } ?: ""), e)
    }
}
