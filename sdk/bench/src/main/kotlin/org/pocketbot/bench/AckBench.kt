package org.pocketbot.bench

import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.delay
import org.pocketbot.sdk.RobotOptions
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.transport.RobotDevice
import java.util.concurrent.locks.LockSupport
import kotlin.random.Random

/**
 * Command to acknowledgement, as a program meets it: a connected [org.pocketbot.sdk.Robot] sends `stop` (an acked
 * command that goes out ahead of everything) and [org.pocketbot.sdk.Locomotion.stop] returns when the robot's ack
 * arrived. The same emulated robot in real time answers every path measured, so the paths differ only in what lies
 * between the SDK and the robot (nothing but a socket, one broker, two bridged brokers).
 */
internal object AckBench {
    class Result(val p50Ms: Double, val p99Ms: Double, val samples: Int)

    suspend fun run(scope: CoroutineScope, device: RobotDevice, samples: Int = 2000, warmup: Int = 300): Result {
        val robot = device.connect(scope, RobotOptions())
        try {
            delay(200) // the connect's own traffic (settings, first states) settles
            repeat(warmup) { robot.locomotion.stop() }
            val ns = LongArray(samples)
            for (i in 0 until samples) {
                // A random pause first: a command sent right after the last ack would meet the emulator's 1 ms step
                // always at the same phase, which hides anything the path adds below a step.
                LockSupport.parkNanos(Random.nextLong(1_000_000))
                val t0 = System.nanoTime()
                robot.locomotion.stop()
                ns[i] = System.nanoTime() - t0
            }
            ns.sort()
            fun pct(p: Double) = ns[minOf(samples - 1, (p * samples).toInt())] / 1e6
            return Result(pct(0.50), pct(0.99), samples)
        } finally {
            robot.disconnect()
        }
    }
}
