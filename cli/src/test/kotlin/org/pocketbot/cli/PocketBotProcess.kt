package org.pocketbot.cli

import java.io.File
import java.io.InputStream
import java.util.concurrent.LinkedBlockingQueue
import java.util.concurrent.TimeUnit
import kotlin.test.fail

/** What `pocketbot` printed and how it exited. */
class Run(val code: Int, val out: String, val err: String) {
    override fun toString() = "exit $code\n--- stdout\n$out--- stderr\n$err"
}

/**
 * The `pocketbot` launcher as `make cli` writes it (cli/launcher.sh), for this test run's classes: every process test
 * runs the command the way a user's shell does.
 */
val launcher: File by lazy {
    val java = File(System.getProperty("java.home"), "bin/java").path
    val out = File("target/test-launcher/pocketbot")
    val made = ProcessBuilder("sh", "launcher.sh", java, System.getProperty("java.class.path"), out.path).inheritIO().start()
    check(made.waitFor(30, TimeUnit.SECONDS) && made.exitValue() == 0) { "cli/launcher.sh failed" }
    out
}

/** How long a loaded CI machine may take for one command: a liveness guard, not a timing assertion. */
const val GUARD_SECONDS = 90L

/**
 * A running `pocketbot` process. Its stdout and stderr are read on their own threads as they come, so neither pipe
 * fills up and blocks it, and a test can act on a line while the command runs ([onLine]). [env] is added to its
 * environment.
 */
class PocketBotProcess(args: List<String>, env: Map<String, String> = emptyMap(), private val onLine: (String) -> Unit = {}) {
    private val process = ProcessBuilder(listOf(launcher.path) + args).apply { environment().putAll(env) }.start()
    private val out = StringBuffer()
    private val err = StringBuffer()
    private val lines = LinkedBlockingQueue<String>()
    private val readers = listOf(
        reader(process.inputStream) { out.append(it).append('\n'); lines.put(it); onLine(it) },
        reader(process.errorStream) { err.append(it).append('\n') },
    )
    private val command = args.joinToString(" ")

    private fun reader(stream: InputStream, each: (String) -> Unit) =
        Thread { stream.bufferedReader().forEachLine(each) }.apply { isDaemon = true; start() }

    /** Writes [line] to the command's stdin. */
    fun send(line: String) = process.outputStream.run { write("$line\n".toByteArray()); flush() }

    /** The next line of stdout that matches [pattern], waiting for it as long as the guard allows. */
    fun awaitLine(pattern: Regex): MatchResult {
        val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(GUARD_SECONDS)
        while (true) {
            val left = deadline - System.nanoTime()
            val line = lines.poll(maxOf(0, left), TimeUnit.NANOSECONDS)
                ?: fail("pocketbot $command printed no line like $pattern within $GUARD_SECONDS s\n${snapshot()}")
            pattern.find(line)?.let { return it }
        }
    }

    /** Waits for the command to end; one that does not end within the guard is killed and fails the test. */
    fun await(): Run {
        if (!process.waitFor(GUARD_SECONDS, TimeUnit.SECONDS)) {
            process.destroyForcibly().waitFor(10, TimeUnit.SECONDS)
            readers.forEach { it.join(5000) }
            fail("pocketbot $command did not end within $GUARD_SECONDS s and was killed\n${snapshot()}")
        }
        readers.forEach { it.join(10_000) }
        return Run(process.exitValue(), out.toString(), err.toString())
    }

    /**
     * Interrupts the command (SIGTERM, as `kill` does) and waits for its end. Through its ProcessHandle: Process.destroy
     * would also close the pipes, and what the command says on its way out would be lost.
     */
    fun interrupt(): Run {
        process.toHandle().destroy()
        return await()
    }

    /** Kills the command if it still runs (test cleanup). */
    fun kill() {
        if (process.isAlive) process.destroyForcibly().waitFor(10, TimeUnit.SECONDS)
    }

    private fun snapshot() = "--- stdout so far\n$out--- stderr so far\n$err"
}

/** Runs `pocketbot ARGS` to its end. */
fun runPocketBot(args: List<String>, env: Map<String, String> = emptyMap(), onLine: (String) -> Unit = {}): Run =
    PocketBotProcess(args, env, onLine).await()
