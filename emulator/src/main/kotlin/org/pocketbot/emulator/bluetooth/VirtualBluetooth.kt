package org.pocketbot.emulator.bluetooth

import java.io.BufferedReader
import java.io.File
import java.io.IOException
import java.io.Writer
import java.net.InetSocketAddress
import java.nio.file.Files
import java.nio.file.Path
import java.nio.file.Paths
import java.util.concurrent.TimeUnit

/**
 * Virtual Bluetooth: Bumble's BR/EDR controllers on one virtual link, each an H4 byte stream on a TCP port for a
 * robot's firmware to drive, and a computer-side gateway that reaches a robot by address and offers its RFCOMM
 * channel (SLIP bytes) and framed L2CAP channel (frames after a 2-byte length) as local TCP endpoints. It runs
 * emulator/bluetooth/virtual_bluetooth.py (see its README) in Bumble's virtual environment, one process for all.
 *
 * ```
 * VirtualBluetooth.start(controllers = 2).use { bt ->
 *     robot.attachH4(bt.controllers[0].h4)                // the robot's UART drives controller 1
 *     val bridge = bt.bridge(bt.controllers[0].address)    // TcpRobotDevice(bridge.rfcomm) reaches it
 * }
 * ```
 * Methods are safe to call from any thread; each command waits for its answer.
 */
public class VirtualBluetooth private constructor(private val process: Process, private val log: Path) : AutoCloseable {
    /** One robot's controller: its Bluetooth address and the H4 endpoint its host (the robot) connects to. */
    public class Controller internal constructor(
        public val index: Int,
        public val address: String,
        public val h4: InetSocketAddress,
    ) {
        override fun toString(): String = "controller $index $address h4 $h4"
    }

    /** The gateway's endpoints for the robot at [address]: RFCOMM as a SLIP byte stream, L2CAP as prefixed frames. */
    public class Bridge internal constructor(
        public val address: String,
        public val rfcomm: InetSocketAddress,
        public val l2cap: InetSocketAddress,
    ) {
        override fun toString(): String = "bridge $address rfcomm $rfcomm l2cap $l2cap"
    }

    private val output: BufferedReader = process.inputStream.bufferedReader()
    private val input: Writer = process.outputStream.bufferedWriter()

    public val controllers: List<Controller>
    public val gatewayAddress: String

    init {
        val cs = ArrayList<Controller>()
        var gateway: String? = null
        while (true) {
            val words = readLine().split(' ')
            when (words[0]) {
                "controller" -> cs += Controller(words[1].toInt(), words[2], endpoint(words[4]))
                "gateway" -> gateway = words[1]
                "ready" -> break
                else -> fail("unexpected line: ${words.joinToString(" ")}")
            }
        }
        controllers = cs
        gatewayAddress = gateway ?: fail("no gateway line")
    }

    /** Opens (or returns) the gateway's TCP endpoints for the robot at [address]. Nothing connects until a client does. */
    public fun bridge(address: String): Bridge {
        val w = command("bridge $address")
        return Bridge(w[2], endpoint(w[4]), endpoint(w[6]))
    }

    /**
     * The radio link between the gateway and the robot at [address] is lost: both sides see a supervision timeout.
     * For [outOfReach] after it, the gateway's pages fail as for a robot out of range; then they reach it again.
     */
    public fun drop(address: String, outOfReach: kotlin.time.Duration = kotlin.time.Duration.ZERO) {
        command("drop $address ${outOfReach.inWholeMilliseconds / 1000.0}")
    }

    /** Controller [index] power-cycles: its links are lost, its state forgotten, and it says nothing to its host. */
    public fun reset(index: Int) { command("reset $index") }

    private fun command(text: String): List<String> = synchronized(this) {
        input.write(text + "\n")
        input.flush()
        val answer = readLine()
        if (!answer.startsWith("ok ")) fail("'$text' failed: $answer")
        answer.split(' ')
    }

    private fun readLine(): String = output.readLine() ?: fail("the process ended")

    private fun fail(why: String): Nothing {
        val tail = runCatching { Files.readAllLines(log).takeLast(20).joinToString("\n") }.getOrDefault("")
        throw IllegalStateException("virtual Bluetooth: $why\n$tail")
    }

    override fun close() {
        runCatching { input.write("quit\n"); input.flush() }
        if (!process.waitFor(3, TimeUnit.SECONDS)) {
            process.destroy()
            if (!process.waitFor(3, TimeUnit.SECONDS)) process.destroyForcibly()
        }
        Files.deleteIfExists(log)
    }

    public companion object {
        /**
         * Starts [controllers] robots' controllers and the gateway; returns when they are ready. [aclLength] and
         * [aclPackets] are the ACL buffers each robot's controller announces (Read_Buffer_Size): 310 bytes x 10 as
         * many BR/EDR modules, or Bumble's own 27 bytes to make the robot fragment everything it sends. [host] is the
         * address every TCP port listens on. Needs Bumble: see [python].
         */
        public fun start(controllers: Int, aclLength: Int = 310, aclPackets: Int = 10, host: String = "127.0.0.1"): VirtualBluetooth {
            require(controllers in 1..254) { "controllers must be 1..254, not $controllers" }
            val script = Files.createTempFile("virtual_bluetooth", ".py")
            VirtualBluetooth::class.java.getResourceAsStream("/bluetooth/virtual_bluetooth.py").use { res ->
                checkNotNull(res) { "virtual_bluetooth.py is not on the class path" }
                Files.copy(res, script, java.nio.file.StandardCopyOption.REPLACE_EXISTING)
            }
            script.toFile().deleteOnExit()
            val log = Files.createTempFile("virtual_bluetooth", ".log")
            val process = ProcessBuilder(python(), "-u", script.toString(), "--controllers", controllers.toString(),
                "--acl-length", aclLength.toString(), "--acl-packets", aclPackets.toString(), "--host", host, "-v")
                .redirectError(log.toFile()).start()
            return try {
                VirtualBluetooth(process, log)
            } catch (e: Exception) {
                process.destroyForcibly()
                throw e
            }
        }

        /**
         * The Python with Bumble in it: the system property `pocketbot.bumble.python`, else the environment variable
         * `POCKETBOT_BUMBLE_PYTHON`, else the one scripts/ensure-bumble.sh installs (it runs, fast when installed)
         * in the PocketBot checkout around the working directory.
         */
        public fun python(): String {
            System.getProperty("pocketbot.bumble.python")?.let { return it }
            System.getenv("POCKETBOT_BUMBLE_PYTHON")?.let { return it }
            var dir: Path? = Paths.get("").toAbsolutePath()
            while (dir != null && !Files.exists(dir.resolve(ENSURE_SCRIPT))) dir = dir.parent
            checkNotNull(dir) {
                "no Bumble: run scripts/ensure-bumble.sh in a PocketBot checkout and set POCKETBOT_BUMBLE_PYTHON to the python it prints"
            }
            val p = ProcessBuilder("bash", dir.resolve(ENSURE_SCRIPT).toString()).redirectError(ProcessBuilder.Redirect.INHERIT).start()
            val python = p.inputStream.bufferedReader().readText().trim().lines().last()
            if (p.waitFor() != 0 || !File(python).canExecute()) throw IOException("$ENSURE_SCRIPT failed (exit ${p.exitValue()})")
            return python
        }

        private const val ENSURE_SCRIPT = "scripts/ensure-bumble.sh"

        private fun endpoint(hostPort: String): InetSocketAddress =
            InetSocketAddress(hostPort.substringBeforeLast(':'), hostPort.substringAfterLast(':').toInt())
    }
}
