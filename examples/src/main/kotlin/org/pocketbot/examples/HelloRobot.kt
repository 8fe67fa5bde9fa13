package org.pocketbot.examples

import kotlinx.coroutines.flow.first
import kotlinx.coroutines.launch
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.runSimulated
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.connect

/**
 * HelloRobot (thesis A.1) rebuilt with the SDK: find a robot, connect, drive a 10 cm square at 0.2 m/s, print the
 * odometry pose on every state update, and at the end compare odometry with the emulator's ground truth.
 *
 * The robot is an embedded emulator (the real firmware in WebAssembly) on simulated time: the run is repeatable
 * (same seed, same numbers) and takes well under a second. Against a real robot only the discoverer changes and the
 * block runs in `runBlocking` instead of `runSimulated`. Run it with `make hello`.
 */
fun main(): Unit = Emulator.local(robots = 1).use { emulator ->
    emulator.runSimulated {
        val device = emulator.discoverer().discover().first()
        println("found ${device.name} at ${device.address}")

        device.connect(this).use { robot ->
            println("robot ${robot.identity.name} (id ${robot.identity.robotId}, firmware ${robot.identity.firmwareVersion}) connected")

            // Odometry starts where the robot really stands, so that the two can be compared at the end.
            val simRobot = emulator.robot(robot.identity.robotId)
            robot.odometry.reset(simRobot.truePose)
            robot.state.first { it.time.timeMs > 0 }

            val printer = launch { robot.odometry.pose.collect { println(it) } }
            repeat(4) {
                robot.locomotion.enqueue(Movement.Straight(distanceM = 0.10, speedMps = 0.2))
                robot.locomotion.enqueue(Movement.Rotate(angleDeg = 90.0, speedMps = 0.2))
            }
            // Until the last movement ended and the robot reported where it stopped.
            robot.locomotion.awaitSettled()
            printer.cancel()

            val odometry = robot.odometry.pose.value
            val truth = simRobot.truePose
            println("odometry pose $odometry")
            println("true pose     $truth")
            println("link: ${robot.linkStats.value}")
            println("pose error ${"%.2f".format(odometry.distanceTo(truth) * 1000)} mm")
        }
    }
}
