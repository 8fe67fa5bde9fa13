package org.pocketbot.sdk.mqtt.testing

import org.pocketbot.sdk.mqtt.BrokerOptions
import java.io.File
import java.net.InetSocketAddress
import java.net.ServerSocket
import java.net.Socket
import java.nio.file.Files
import java.nio.file.attribute.PosixFilePermissions
import java.util.concurrent.TimeUnit

/**
 * A real Mosquitto broker for tests, run with the project's shipped configuration (deploy/mosquitto/mosquitto.conf
 * and its acl) as it is, but for its ports (free loopback ports found at start) and its paths (a temporary folder
 * with certificates made by deploy/mosquitto/make-certs.sh and a password file made by mosquitto_passwd for every
 * user of [USERS]). [start] returns once the broker accepts connections on both listeners.
 *
 * ```
 * MosquittoBroker.start().use { broker ->
 *     val client = connectBroker(broker.options("alice"))       // mqtts, with alice's password and the test CA
 *     broker.freeze(); delay(3.seconds); broker.thaw()           // SIGSTOP, SIGCONT
 *     broker.kill(); broker.restart()                            // SIGKILL, then the same ports again
 * }
 * ```
 *
 * [extraConfig] lines are appended to the configuration, e.g. a bridge to another broker (`connection ...`,
 * `address 127.0.0.1:${central.tlsPort}`, `remote_username bridge`, `remote_password ${central.password("bridge")}`,
 * `bridge_cafile ${central.caFile}`). The broker's log (its stderr) is [log]; it is shown when the broker fails to
 * start.
 */
class MosquittoBroker private constructor(
    /** The temporary folder of the configuration, certificates, password file and log; deleted by [close]. */
    val dir: File,
    /** The TLS listener's port (the shipped configuration's 8883). */
    val tlsPort: Int,
    /** The plain listener's port on 127.0.0.1 (the shipped configuration's 1883). */
    val plainPort: Int,
) : AutoCloseable {
    private var process: Process? = null

    /** `mqtts://127.0.0.1:<tlsPort>`: what hosts other than the broker's use. */
    val url: String get() = "mqtts://127.0.0.1:$tlsPort"

    /** `mqtt://127.0.0.1:<plainPort>`: plain MQTT, for tools on the broker's host. */
    val plainUrl: String get() = "mqtt://127.0.0.1:$plainPort"

    /** The certificate authority that signed the broker's certificate: what clients trust. */
    val caFile: File get() = File(dir, "ca.crt")

    /** The broker's log so far (its stderr). */
    val log: File get() = File(dir, "mosquitto.log")

    /** The operating system's process id of the running broker. */
    val pid: Long get() = checkNotNull(process) { "the broker is not running" }.pid()

    /** True while the broker process runs (frozen included). */
    val running: Boolean get() = process?.isAlive == true

    /** The password of [user] (one of [USERS]) in this broker's password file. */
    fun password(user: String): String {
        require(user in USERS) { "$user is not one of the test broker's users $USERS" }
        return "pw-$user-${dir.name.takeLast(6)}"
    }

    /**
     * Options to connect as [user] (one of [USERS], or null for an anonymous client): TLS with the test CA unless
     * [tls] is false (then the plain listener), the user's password, then [build] for anything else.
     */
    fun options(user: String?, tls: Boolean = true, build: BrokerOptions.Builder.() -> Unit = {}): BrokerOptions =
        BrokerOptions(if (tls) url else plainUrl) {
            if (user != null) {
                username = user
                password = password(user).toCharArray()
            }
            if (tls) trustedCertificates = caFile
            build()
        }

    /** Stops the broker with SIGTERM (a clean shutdown: clients see their connection closed) and waits for it. */
    fun stop() {
        val p = process ?: return
        thaw()
        p.destroy()
        if (!p.waitFor(10, TimeUnit.SECONDS)) p.destroyForcibly().waitFor()
        process = null
    }

    /** Kills the broker with SIGKILL (a crash: nothing is said to clients) and waits for it. */
    fun kill() {
        val p = process ?: return
        p.destroyForcibly().waitFor()
        process = null
    }

    /** Freezes the broker with SIGSTOP: its connections stay open but nothing moves until [thaw]. */
    fun freeze() = signal("STOP")

    /** Lets a [freeze]d broker run again (SIGCONT). */
    fun thaw() = signal("CONT")

    /** Starts the broker again on the same ports, after [stop] or [kill] (stops it first if it runs). */
    fun restart() {
        stop()
        launch()
    }

    /** Stops the broker and deletes [dir]. */
    override fun close() {
        stop()
        dir.deleteRecursively()
    }

    private fun signal(name: String) {
        val p = process ?: return
        val kill = ProcessBuilder("kill", "-$name", p.pid().toString()).redirectErrorStream(true).start()
        check(kill.waitFor(5, TimeUnit.SECONDS) && kill.exitValue() == 0) { "kill -$name ${p.pid()} failed" }
    }

    private fun launch() {
        // Appends: a restart's log follows the first run's.
        val p = ProcessBuilder(mosquitto(), "-c", File(dir, "mosquitto.conf").path)
            .redirectErrorStream(true)
            .redirectOutput(ProcessBuilder.Redirect.appendTo(log))
            .start()
        process = p
        val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(START_TIMEOUT_SECONDS)
        while (!(accepts(tlsPort) && accepts(plainPort))) {
            if (!p.isAlive) {
                process = null
                error("mosquitto exited with ${p.exitValue()} at start:\n${log.readText()}")
            }
            if (System.nanoTime() > deadline) {
                kill()
                error("mosquitto did not accept connections within $START_TIMEOUT_SECONDS s:\n${log.readText()}")
            }
            Thread.sleep(10)
        }
    }

    companion object {
        /** The users of the test broker's password file, as the shipped acl names them: gateways, a driver, a watcher, a bridge. */
        val USERS: List<String> = listOf("lab1", "lab2", "alice", "bob", "bridge")

        private const val START_TIMEOUT_SECONDS = 10L

        /**
         * Starts a broker with the shipped configuration, plus [extraConfig] lines at its end, on free loopback ports
         * (or the given ones), and waits until it accepts connections.
         */
        fun start(extraConfig: List<String> = emptyList(), tlsPort: Int = freePort(), plainPort: Int = freePort()): MosquittoBroker {
            val dir = Files.createTempDirectory("pocketbot-mosquitto-").toFile()
            val broker = MosquittoBroker(dir, tlsPort, plainPort)
            try {
                broker.prepare(extraConfig)
                broker.launch()
            } catch (e: Throwable) {
                broker.close()
                throw e
            }
            return broker
        }

        /** The shipped broker configuration: deploy/mosquitto of the checkout these tests run in. */
        val deployDir: File by lazy {
            generateSequence(File("").absoluteFile) { it.parentFile }
                .map { File(it, "deploy/mosquitto") }
                .firstOrNull { File(it, "mosquitto.conf").isFile }
                ?: error("no deploy/mosquitto/mosquitto.conf above ${File("").absolutePath}")
        }

        /** A TCP port free on loopback now. */
        fun freePort(): Int = ServerSocket(0, 1, java.net.InetAddress.getLoopbackAddress()).use { it.localPort }

        private fun accepts(port: Int): Boolean = try {
            Socket().use { it.connect(InetSocketAddress("127.0.0.1", port), 200); true }
        } catch (e: java.io.IOException) {
            false
        }

        private fun mosquitto(): String =
            listOf("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto").firstOrNull { File(it).canExecute() } ?: "mosquitto"

        private fun run(vararg command: String) {
            val p = ProcessBuilder(*command).redirectErrorStream(true).start()
            val output = p.inputStream.readBytes().toString(Charsets.UTF_8)
            check(p.waitFor() == 0) { "${command.joinToString(" ")} failed: $output" }
        }
    }

    /** Certificates, password file, acl and the configuration with ports and paths replaced, in [dir]. */
    private fun prepare(extraConfig: List<String>) {
        run("bash", File(deployDir, "make-certs.sh").path, dir.path, "localhost")
        val passwd = File(dir, "passwd")
        for ((i, user) in USERS.withIndex()) {
            if (i == 0) run("mosquitto_passwd", "-b", "-c", passwd.path, user, password(user))
            else run("mosquitto_passwd", "-b", passwd.path, user, password(user))
        }
        File(deployDir, "acl").copyTo(File(dir, "acl"))
        val replaced = mutableSetOf<String>()
        val config = File(deployDir, "mosquitto.conf").readLines().map { line ->
            val key = line.substringBefore(' ')
            val value = when {
                line == "listener 8883" -> "listener $tlsPort 127.0.0.1"
                line == "listener 1883 127.0.0.1" -> "listener $plainPort 127.0.0.1"
                key == "password_file" -> "password_file ${passwd.path}"
                key in setOf("acl_file", "cafile", "certfile", "keyfile") ->
                    "$key ${File(dir, mapOf("acl_file" to "acl", "cafile" to "ca.crt", "certfile" to "server.crt", "keyfile" to "server.key").getValue(key)).path}"
                else -> return@map line
            }
            replaced += if (key == "listener") line else key
            value
        }
        val expected = setOf("listener 8883", "listener 1883 127.0.0.1", "password_file", "acl_file", "cafile", "certfile", "keyfile")
        check(replaced == expected) { "deploy/mosquitto/mosquitto.conf changed: the test broker replaced ${replaced.sorted()}, expected ${expected.sorted()}" }
        File(dir, "mosquitto.conf").writeText((config + "" + "# tests" + "log_dest stderr" + extraConfig).joinToString("\n", postfix = "\n"))
        // Run as root, mosquitto drops to its own user before it reads the files: let it.
        Files.setPosixFilePermissions(dir.toPath(), PosixFilePermissions.fromString("rwxr-xr-x"))
        dir.listFiles()!!.forEach { Files.setPosixFilePermissions(it.toPath(), PosixFilePermissions.fromString("rw-r--r--")) }
    }
}
