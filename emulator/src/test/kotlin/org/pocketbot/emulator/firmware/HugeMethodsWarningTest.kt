package org.pocketbot.emulator.firmware

import java.io.File
import java.util.concurrent.TimeUnit
import kotlin.test.Test
import kotlin.test.assertContains
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertTrue

/** Loads the compiled firmware in a JVM started without the flag, as a user's program would, and prints nothing else. */
object LoadCompiledFirmware {
    @JvmStatic
    fun main(args: Array<String>) {
        FirmwareImage.compiled()
        FirmwareImage.compiled() // the warning comes once
    }
}

/**
 * The emulator tells a user whose JVM leaves the firmware's huge methods interpreted, and is quiet otherwise. The
 * huge methods are Chicory's: the probe runs the firmware on Chicory unless told otherwise.
 */
class HugeMethodsWarningTest {
    private fun loadIn(vararg jvmFlags: String, engine: String = "chicory"): String {
        val java = File(System.getProperty("java.home"), "bin/java").path
        val cmd = listOf(java, *jvmFlags, "-D${FirmwareImage.ENGINE_PROPERTY}=$engine", "-cp", System.getProperty("java.class.path"), LoadCompiledFirmware::class.java.name)
        val log = File.createTempFile("firmware-probe", ".txt").apply { deleteOnExit() }
        val process = ProcessBuilder(cmd).redirectErrorStream(true).redirectOutput(log).start()
        val ended = process.waitFor(60, TimeUnit.SECONDS)
        if (!ended) process.destroyForcibly().waitFor()
        val output = log.readText()
        assertTrue(ended, "the probe JVM did not end: $output")
        assertEquals(0, process.exitValue(), output)
        return output
    }

    @Test
    fun `a JVM without -XX-DontCompileHugeMethods gets one warning naming the flag`() {
        val output = loadIn()
        assertEquals(1, Regex("-XX:-DontCompileHugeMethods").findAll(output).count(), "expected one warning, got:\n$output")
        assertTrue("WARNING" in output, output)
    }

    @Test
    fun `a JVM with the flag gets no warning`() {
        val output = loadIn("-XX:-DontCompileHugeMethods")
        assertFalse("WARNING" in output || "DontCompileHugeMethods" in output, output)
        assertContains(output, "the firmware runs on Chicory, as asked")
    }

    @Test
    fun `firmware run natively gets no warning, whatever the flag`() {
        val output = loadIn(engine = "native")
        assertFalse("WARNING" in output || "DontCompileHugeMethods" in output, output)
        assertContains(output, "the firmware runs natively")
    }
}
