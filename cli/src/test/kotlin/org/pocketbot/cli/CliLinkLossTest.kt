package org.pocketbot.cli

import kotlinx.serialization.json.jsonPrimitive
import org.junit.jupiter.api.Test
import java.io.File
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/**
 * `pocketbot` as a user meets a robot that goes away: the emulator is a process of its own (`pocketbot emulator`),
 * killed with SIGKILL in the middle of a command, and in one case started again on the same port.
 */
class CliLinkLossTest {
    /** `pocketbot emulator` with one robot on a free port of this machine (or on [port], for a restart). */
    private class EmulatorProcess(port: Int = 0) : AutoCloseable {
        private val process = PocketBotProcess(listOf("emulator", "--robots", "1", "--world", "straight", "--port-base", "$port", "--control-port", "-1"))
        val port: Int = process.awaitLine(Regex("""^robot 1 PocketBot-1 tcp 127\.0\.0\.1:(\d+)""")).groupValues[1].toInt()
        val address = "tcp://127.0.0.1:${this.port}"

        /** Kills the emulator as a crash or `kill -9` does: no goodbye, the kernel closes its sockets. */
        fun kill() = process.kill()

        override fun close() = process.kill()
    }

    /** True when a TCP connection to local [port] is established (a client of the emulator's robot). */
    private fun connectedTo(port: Int): Boolean = listOf("/proc/net/tcp", "/proc/net/tcp6").any { table ->
        File(table).takeIf { it.exists() }?.readLines()?.drop(1)?.any { line ->
            val cols = line.trim().split(Regex("\\s+"))
            cols[1].substringAfter(':').toInt(16) == port && cols[3] == "01"
        } ?: false
    }

    /** Starts `move ... --wait` on [emulator]'s robot and returns it once the robot drove for a while. */
    private fun movingRobot(emulator: EmulatorProcess): PocketBotProcess {
        val move = PocketBotProcess(listOf("move", emulator.address, "straight", "1.0", "--speed", "0.1", "--wait", "--json"))
        until("pocketbot is connected to the robot") { connectedTo(emulator.port) }
        Thread.sleep(2500) // the robot drives about 0.2 m of its 1.0 m
        return move
    }

    /** [run] (the 1.0 m move) ended with exit 5, its movement `lost`, and part of the distance as this host saw it. */
    private fun assertLostWithTheDistanceSeen(run: Run) {
        assertEquals(5, run.code, "$run")
        val row = jsonLines(run.out).single()
        assertEquals("lost", row["outcome"]!!.jsonPrimitive.content, "$run")
        val done = row["done"]!!.jsonPrimitive.content.toDouble()
        assertTrue(done in 0.05..0.9, "the distance the host saw the robot drive, $done m of 1.0 m: $run")
    }

    @Test
    fun aMoveWaitingForARobotWhoseEmulatorWasKilledEndsWithTheDistanceItSawAndExit5() {
        val emulator = EmulatorProcess()
        val move = try { movingRobot(emulator) } finally { emulator.kill() }
        // Nothing comes back: the command gives up on its own, bounded, and says what it knows.
        val run = move.await()
        assertLostWithTheDistanceSeen(run)
        assertTrue(run.err.contains("lost the link to PocketBot-1"), "$run")
        assertTrue(!run.err.contains("Lost(") && !run.err.contains("reason="), "no internal names: $run")
    }

    @Test
    fun aMoveWaitingForARobotWhoseEmulatorWasRestartedEndsWithTheDistanceItSawAndExit5() {
        val emulator = EmulatorProcess()
        val port = emulator.port
        val move = try { movingRobot(emulator) } finally { emulator.kill() }
        // The robot is back at once, restarted: it has no record of the movement.
        EmulatorProcess(port).use { again ->
            assertLostWithTheDistanceSeen(move.await())
            // The restarted robot serves the next command as usual.
            val info = runPocketBot(listOf("info", again.address, "--json"))
            assertEquals(0, info.code, "$info")
        }
    }
}
