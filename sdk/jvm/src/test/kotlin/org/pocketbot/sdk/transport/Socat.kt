package org.pocketbot.sdk.transport

import java.io.File
import java.nio.file.Files
import java.util.concurrent.TimeUnit

/**
 * A `socat` process for tests: a pseudo-terminal pair ([ptyPair]) or a pty bridged to a TCP port ([ptyToTcp]).
 * The ptys appear as symlinks in a fresh temporary folder; closing kills socat, which takes the ptys away.
 */
class Socat private constructor(args: List<String>, val links: List<File>) : AutoCloseable {
    private val log = File.createTempFile("socat", ".log")
    private val process: Process = ProcessBuilder(listOf("socat", "-d", "-d") + args)
        .redirectErrorStream(true).redirectOutput(log).start()

    init {
        val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(10)
        while (!links.all { it.exists() }) {
            check(process.isAlive) { "socat ended: ${log.readText()}" }
            check(System.nanoTime() < deadline) { "socat made no ptys within 10 s: ${log.readText()}" }
            Thread.sleep(20)
        }
    }

    /** The real device of [link] (`/dev/pts/N`). */
    fun realPath(link: File): String = link.toPath().toRealPath().toString()

    override fun close() {
        process.destroy()
        if (!process.waitFor(5, TimeUnit.SECONDS)) process.destroyForcibly().waitFor()
        log.delete()
    }

    companion object {
        val available: Boolean by lazy {
            runCatching { ProcessBuilder("socat", "-V").redirectErrorStream(true).start().waitFor() == 0 }
                .getOrDefault(false)
        }

        private fun folder(): File = Files.createTempDirectory("pocketbot-pty").toFile().apply { deleteOnExit() }

        /** Two ptys wired to each other: what one is written, the other reads. */
        fun ptyPair(): Socat {
            val dir = folder()
            val a = File(dir, "host")
            val b = File(dir, "robot")
            return Socat(listOf("pty,raw,echo=0,link=$a", "pty,raw,echo=0,link=$b"), listOf(a, b))
        }

        /** A pty whose other end is a TCP connection to 127.0.0.1:[port] (made when socat starts). */
        fun ptyToTcp(port: Int): Socat {
            val a = File(folder(), "host")
            return Socat(listOf("pty,raw,echo=0,link=$a", "tcp:127.0.0.1:$port"), listOf(a))
        }
    }
}
