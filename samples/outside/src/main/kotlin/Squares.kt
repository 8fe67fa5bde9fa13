import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.runSimulated
import org.pocketbot.sdk.Fleet
import org.pocketbot.sdk.Movement

/** Three emulated robots each drive a 20 cm square at the same time; then odometry is compared with ground truth. */
fun main() = Emulator.local(robots = 3, world = "open").use { emulator ->
    emulator.runSimulated {
        val fleet = Fleet(this)
        val robots = fleet.discoverAndConnect(emulator.discoverer(), count = 3)
        for (robot in robots) robot.odometry.reset(emulator.robot(robot.identity.robotId).truePose)
        val square = List(4) { listOf(Movement.Straight(distanceM = 0.2, speedMps = 0.1), Movement.Rotate(angleDeg = 90.0, speedMps = 0.1)) }
        fleet.runTogether(robots.associateWith { square.flatten() })
        fleet.awaitSettled() // the odometry of the states after the last movement
        for (robot in robots) {
            val odometry = robot.odometry.pose.value
            val truth = emulator.robot(robot.identity.robotId).truePose
            println("${robot.identity.name}: odometry $odometry, truth $truth, " +
                "off by %.1f mm and %.1f deg".format(odometry.distanceTo(truth) * 1000, odometry.headingDeg - truth.headingDeg))
        }
        fleet.disconnect()
    }
}
