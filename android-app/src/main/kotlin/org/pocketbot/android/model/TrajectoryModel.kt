package org.pocketbot.android.model

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.SharingStarted
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.flow.stateIn
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.TrajectoryPoint

/** The path so far (odometry) and where the robot is now. */
class TrajectoryView(val points: List<TrajectoryPoint>, val pose: Pose, val lengthM: Double)

/** The robot's dead-reckoned path, live, from the SDK's odometry. */
class TrajectoryModel(private val robot: Robot, scope: CoroutineScope, private val act: (String, suspend () -> Unit) -> Unit) {
    private val trajectory = robot.odometry.trajectory

    val view: StateFlow<TrajectoryView> = combine(trajectory.points, robot.odometry.pose) { points, pose ->
        TrajectoryView(points, pose, trajectory.lengthM)
    }.stateIn(scope, SharingStarted.Eagerly, TrajectoryView(trajectory.points.value, robot.odometry.pose.value, trajectory.lengthM))

    /** Starts the path again from here: the robot's position becomes the origin. */
    fun clear() = act("clear the path") { robot.odometry.reset() }
}
