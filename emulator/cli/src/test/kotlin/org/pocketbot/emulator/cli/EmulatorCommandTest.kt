package org.pocketbot.emulator.cli

import java.io.File
import java.util.concurrent.TimeUnit
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertTrue

/** The emulator's command line as a user runs it: a process of its own. */
class EmulatorCommandTest {
    /** Runs the emulator command with [args] until it ends (or 60 s, then it is killed); its exit code and output. */
    private fun emulator(vararg args: String): Pair<Int, String> {
        val java = File(System.getProperty("java.home"), "bin/java").path
        val cmd = listOf(java, "-XX:-DontCompileHugeMethods", "-cp", System.getProperty("java.class.path"), "org.pocketbot.emulator.cli.MainKt", *args)
        val log = File.createTempFile("emulator-cli", ".txt").apply { deleteOnExit() }
        val process = ProcessBuilder(cmd).redirectErrorStream(true).redirectOutput(log).start()
        process.outputStream.close()
        val ended = process.waitFor(60, TimeUnit.SECONDS)
        if (!ended) process.destroyForcibly().waitFor()
        val output = log.readText()
        assertTrue(ended, "the emulator did not end: $output")
        return process.exitValue() to output
    }

    @Test
    fun `more robots than the world has room for is an error that says so, not a pile of robots`() {
        // The straight world's 1.2 x 0.3 m floor holds its 2 start poses and about 45 robots beside the line.
        val (code, output) = emulator("--robots", "100", "--world", "straight", "--port-base", "0", "--control-port", "-1")
        assertEquals(1, code, output)
        assertTrue("no room for another robot in world straight" in output, output)
        assertTrue("Exception" !in output, "a stack trace instead of a message: $output")
    }
}
