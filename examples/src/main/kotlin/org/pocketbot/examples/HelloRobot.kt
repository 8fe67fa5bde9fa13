package org.pocketbot.examples

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import kotlinx.coroutines.runBlocking
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.Pose
import org.pocketbot.sdk.connect
import kotlin.math.PI
import kotlin.math.hypot

/**
 * HelloRobot (thesis A.1) rebuilt with the SDK: find a robot, connect, drive a 10 cm square at 0.2 m/s, print the
 * odometry pose on every state update, and at the end compare odometry with the emulator's ground truth.
 *
 * The robot is an embedded emulator (the real firmware in WebAssembly) running in real time; against a real robot
 * only the discoverer changes. Run it with `make hello`.
 */
fun main(): Unit = runBlocking {
    Emulator.local(robots = 1).use { emulator ->
        emulator.start(Speed.Realtime(1.0))
        val device = emulator.discoverer().discover().first()
        println("found ${device.name} at ${device.address}")

        val robot = device.connect(this)
        println("robot ${robot.identity.name} (id ${robot.identity.robotId}, firmware ${robot.identity.firmwareVersion}) connected")

        // Odometry starts where the robot really stands, so that the two can be compared at the end.
        val simRobot = emulator.robot(robot.identity.robotId)
        val start = simRobot.truePose
        robot.odometry.reset(Pose(start.x, start.y, start.headingDeg * PI / 180))
        robot.state.first { it.time.timeMs > 0 }

        val printer = launch { robot.odometry.pose.collect { println(it) } }

        val speed = 0.2
        val length = 0.1
        val angle = 90.0
        repeat(4) {
            robot.locomotion.enqueue(Movement.Straight(distanceM = length, speedMps = speed))
            robot.locomotion.enqueue(Movement.Rotate(angleDeg = angle, speedMps = speed))
        }
        robot.locomotion.awaitIdle()

        // Let the last state packet after the stop arrive.
        val finished = robot.state.value.time.timeMs
        robot.state.first { it.time.timeMs >= finished + 2 * robot.reflector.period.value.inWholeMilliseconds }
        printer.cancel()

        val odometry = robot.odometry.pose.value
        val truth = simRobot.truePose
        val truePose = Pose(truth.x, truth.y, truth.headingDeg * PI / 180)
        val errorMm = hypot(odometry.xM - truePose.xM, odometry.yM - truePose.yM) * 1000
        println("odometry pose $odometry")
        println("true pose     $truePose")
        println("link: ${robot.linkStats.value}")
        robot.close()
        emulator.stop()
        println("pose error ${"%.2f".format(errorMm)} mm")
    }
}
