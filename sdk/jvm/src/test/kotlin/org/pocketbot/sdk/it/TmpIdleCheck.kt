package org.pocketbot.sdk.it

import kotlinx.coroutines.flow.first
import org.junit.jupiter.api.Test
import org.pocketbot.sdk.Movement
import kotlin.time.Duration.Companion.milliseconds

/** Temporary probe (not to be merged): how far odometry after awaitIdle is from the final one. */
class TmpIdleCheck {
    @Test
    fun probe() = withEmulator(world = "open") { emu ->
        for (period in listOf(50, 300)) {
            val robot = connectAll(emu).single()
            robot.reflector.set(robot.reflector.mode.value, period.milliseconds)
            repeat(4) { robot.locomotion.enqueue(Movement.Straight(0.10, 0.2)); robot.locomotion.enqueue(Movement.Rotate(90.0, 0.2)) }
            robot.locomotion.awaitIdle()
            val idle = robot.odometry.pose.value
            val at = robot.state.value.time.timeMs
            robot.state.first { it.time.timeMs > at + 5 * period }
            val later = robot.odometry.pose.value
            println("PROBE period $period ms: after awaitIdle $idle, later $later, apart ${idle.distanceTo(later) * 1000} mm, ${later.headingDeg - idle.headingDeg} deg")
            robot.disconnect()
        }
    }
}
