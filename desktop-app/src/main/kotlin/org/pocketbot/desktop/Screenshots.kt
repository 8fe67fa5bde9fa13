package org.pocketbot.desktop

import androidx.compose.runtime.Composable
import androidx.compose.runtime.LaunchedEffect
import androidx.compose.runtime.MutableState
import androidx.compose.ui.awt.ComposeWindow
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.withContext
import org.pocketbot.desktop.model.PanelModel
import org.pocketbot.desktop.ui.View
import org.pocketbot.sdk.Controller
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.Role
import org.pocketbot.sdk.StaleReason
import org.pocketbot.sdk.connect
import java.awt.Rectangle
import java.io.File
import javax.imageio.ImageIO

/**
 * `make screenshots`: drives the real panel (under Xvfb) through its main views with the embedded fleet running and
 * writes a PNG of the window for each to [dir], the panel watching a robot another host took over, the sensors of a
 * robot whose link went down (`stale`), the overview, the world and the track behaviour's card on the track world with
 * the behaviour running (thesis A.3), then calls [done].
 */
@Composable
fun Screenshots(window: ComposeWindow, model: PanelModel, view: MutableState<View>, dir: File, done: () -> Unit) {
    LaunchedEffect(Unit) {
        dir.mkdirs()
        val robots = model.robots.first { it.size == (model.emulator?.world?.value?.robots?.size ?: 0) && it.isNotEmpty() }
        delay(6000) // the fleet gets going: paths, line readings, a console
        suspend fun shoot(v: View, name: String, settle: Long = 1500) {
            view.value = v
            delay(settle)
            val bounds = withContext(Dispatchers.Main) { Rectangle(window.locationOnScreen, window.size) }
            val image = java.awt.Robot().createScreenCapture(bounds)
            ImageIO.write(image, "png", File(dir, "$name.png"))
            println("screenshot ${File(dir, "$name.png")}")
        }
        shoot(View.SENSORS, "sensors")
        shoot(View.SETTINGS, "settings")
        shoot(View.TRAJECTORY, "trajectory")
        // Tuning: the first robot leaves the line for a wheel speed step test, captured and charted.
        val tuned = robots.first()
        model.select(tuned)
        tuned.stopLineFollowing()
        tuned.tuning.choose(Controller.WHEEL_SPEED)
        tuned.tuning.start()
        view.value = View.TUNING
        delay(1000)
        tuned.tuning.stepTest()
        tuned.tuning.running.first { it }
        tuned.tuning.running.first { !it }
        shoot(View.TUNING, "tuning", settle = 2500)
        // Commands: the tuned robot back in full sync (live mode and queue), with a few movements and their results.
        tuned.tuning.stop()
        view.value = View.COMMANDS
        for (m in listOf(Movement.Rotate(90.0, 0.15), Movement.Straight(0.05, 0.15), Movement.Arc(0.08, 60.0, 0.15))) tuned.enqueue(m)
        tuned.movements.first { it.size == 3 && it.all { m -> m.result != null } }
        tuned.enqueue(Movement.Straight(0.3, 0.1))
        shoot(View.COMMANDS, "commands")
        // Another host (as `pocketbot --take-over` does) takes the robot over: the panel watches it and says who drives.
        tuned.movements.first { it.last().result != null }
        val other = tuned.emulated!!.device().connect(this, RobotOptions { role = Role.TAKE_OVER; hostLabel = "cli@lab-pc" })
        other.locomotion.enqueue(Movement.Rotate(180.0, 0.1))
        tuned.driving.first { !it.byThisHost }
        shoot(View.COMMANDS, "watching")
        other.disconnect()
        tuned.driving.first { it.byThisHost }
        // What the user was told of it (taken over, then driving again) is not part of the next views.
        model.notices.first { n -> n.any { it.text.startsWith("this panel drives") } }.forEach(model::dismiss)
        // Track (thesis A.3): three robots on the track world running the behaviour: the overview with its track
        // column, the world with the token holder's orange light, and the token holder's Commands view.
        tuned.movements.first { it.last().result != null } // ended before its robot goes with the old world
        // Stale: a robot whose link went down (its emulator's link cut), every value greyed with its age.
        val gone = robots.last()
        model.select(gone)
        gone.emulated?.disconnectLink()
        gone.robot.freshness.first { it.reduced.staleBecause == StaleReason.LINK_DOWN }
        shoot(View.SENSORS, "stale", settle = 5000)
        gone.emulated?.reconnectLink()
        model.restartEmulator("track", 3)
        val onTrack = model.robots.first { it.size == 3 && it.none { r -> r in robots } }
        model.everyRobot { it.startTrack() }
        delay(8000) // the robots get going and meet
        fun selectTokenHolder() = model.select(onTrack.firstOrNull { it.robot.track.holdsToken } ?: onTrack.first())
        selectTokenHolder()
        shoot(View.OVERVIEW, "overview")
        shoot(View.WORLD, "world")
        selectTokenHolder() // the token has moved on meanwhile, most likely
        shoot(View.COMMANDS, "track")
        done()
    }
}
