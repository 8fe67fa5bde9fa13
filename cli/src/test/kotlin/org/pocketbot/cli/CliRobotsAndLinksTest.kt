package org.pocketbot.cli

import kotlinx.serialization.json.jsonPrimitive
import org.junit.jupiter.api.Assumptions.assumeFalse
import org.junit.jupiter.api.Assumptions.assumeTrue
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.ForeignPeer
import org.pocketbot.emulator.Speed
import org.pocketbot.protocol.Colour
import org.pocketbot.protocol.ProtocolInfo
import java.io.File
import java.net.Inet4Address
import java.net.NetworkInterface
import java.util.concurrent.TimeUnit
import kotlin.test.assertEquals
import kotlin.test.assertFalse
import kotlin.test.assertTrue

/**
 * `pocketbot` against robots of their own: a fresh robot for EEPROM and defaults, the colour track, peers that are no
 * robot of this protocol, a robot that goes away, the emulator as a `pocketbot` subcommand, and a terminal.
 */
class CliRobotsAndLinksTest {
    /** Runs [block] with a fresh emulator of [robots] robots on [world], on TCP, found through its control port. */
    private fun <T> withRobots(robots: Int = 1, world: String = "straight", block: (Emulator, List<String>) -> T): T =
        Emulator.local(robots = robots, world = world).use { emu ->
            val port = emu.startTcp(basePort = 0, controlPort = 0)
            emu.start(Speed.Realtime(1.0))
            block(emu, listOf("--control-port", port.toString(), "--sources", "emulator", "--scan-seconds", "2"))
        }

    @Test
    fun savedSettingsSurviveAResetAndDefaultsBringBackTheFirmwaresOwn() = withRobots { emu, global ->
        val default = robotFloat(emu, "line_pid.kd", 1)
        assertEquals(0, runPocketBot(global + listOf("settings", "set", "PocketBot-1", "line_pid.kd", "0.125")).code)
        val save = runPocketBot(global + listOf("settings", "save", "PocketBot-1", "--json"))
        assertEquals(0, save.code, "$save")
        assertEquals("saved", jsonLines(save.out).single()["status"]!!.jsonPrimitive.content)
        assertEquals(0, runPocketBot(global + listOf("settings", "set", "PocketBot-1", "line_pid.kd", "0.25")).code, "changed, not saved")

        emu.robot(1).reset() // a power cycle: the firmware starts from its EEPROM
        until("the robot runs on what it saved") { robotFloat(emu, "line_pid.kd", 1) == 0.125f }

        val defaults = runPocketBot(global + listOf("settings", "defaults", "PocketBot-1"))
        assertEquals(0, defaults.code, "$defaults")
        assertTrue(defaults.out.contains("defaults loaded"), "$defaults")
        assertEquals(default, robotFloat(emu, "line_pid.kd", 1), "the firmware's default is back")
        val get = runPocketBot(global + listOf("settings", "get", "PocketBot-1", "line_pid.kd", "--json"))
        assertEquals(default.toString(), jsonLines(get.out).single()["value"]!!.jsonPrimitive.content, "and read back as such: $get")
    }

    @Test
    fun followWithColoursSlowsDownOnRedTape() = withRobots(world = "colours") { emu, global ->
        val start = runPocketBot(global + listOf("follow", "PocketBot-1", "start", "--speed", "0.15", "--colours"))
        assertEquals(0, start.code, "$start")
        val robot = emu.robot(1)
        until("the robot reaches the red segment") { robot.state().lineFollow.segment == Colour.RED }
        val onRed = robot.state().time.timeMs
        until("half a second of robot time on red") { robot.state().time.timeMs > onRed + 500 }
        val speed = robot.state().wheels.let { (it.speedLeftMmps + it.speedRightMmps) / 2 }
        // line_follow.red_speed_mps is 0.07 by default: plain following would keep 0.15 m/s here.
        assertTrue(speed in 40..100, "on red at $speed mm/s")
        val stop = runPocketBot(global + listOf("follow", "PocketBot-1", "stop"))
        assertEquals(0, stop.code, "$stop")
        until("the follower is off") { robot.state().locomotion.mode.name != "LINE_FOLLOW" }
    }

    @Test
    fun aRobotWithOtherFirmwareExitsWith6() = ForeignPeer(answer = true, protocolVersion = ProtocolInfo.VERSION + 1).use { peer ->
        val run = runPocketBot(listOf("info", peer.address))
        assertEquals(6, run.code, "$run")
        assertTrue(run.err.contains("protocol mismatch") && run.err.contains("v${ProtocolInfo.VERSION + 1}"), "$run")
        ForeignPeer(answer = true, layoutHash = ProtocolInfo.LAYOUT_HASH xor 0xFF).use { other ->
            val layout = runPocketBot(listOf("info", other.address))
            assertEquals(6, layout.code, "the same version with another layout is a mismatch too: $layout")
        }
    }

    @Test
    fun aPeerThatNeverSaysHelloExitsWith7() = ForeignPeer(answer = false).use { peer ->
        val run = runPocketBot(listOf("info", peer.address))
        assertEquals(7, run.code, "$run")
        assertTrue(run.err.contains("hello_request not acknowledged"), "$run")
        val nobody = runPocketBot(listOf("info", "tcp://127.0.0.1:1"))
        assertEquals(5, nobody.code, "nothing listening is no timeout but a link that cannot be made: $nobody")
        assertEquals(1, Regex("127\\.0\\.0\\.1:1\\b").findAll(nobody.err).count(), "the address once: $nobody")
        assertTrue(nobody.err.contains("connection refused", ignoreCase = true), "$nobody")
    }

    @Test
    fun aWrongAddressIsAUsageErrorThatSaysWhatIsWrong() {
        val noPort = runPocketBot(listOf("info", "tcp://127.0.0.1"))
        assertEquals(2, noPort.code, "$noPort")
        assertTrue(noPort.err.contains("'tcp://127.0.0.1' has no port: write tcp://127.0.0.1:PORT"), "$noPort")
        val badPort = runPocketBot(listOf("info", "tcp://127.0.0.1:70000"))
        assertEquals(2, badPort.code, "$badPort")
        assertTrue(badPort.err.contains("'70000' in 'tcp://127.0.0.1:70000' is not a TCP port (1..65535)"), "$badPort")
    }

    @Test
    fun aSpeedWrittenAfterTheDistanceIsAUsageErrorThatNamesTheOption() {
        val r = runPocketBot(listOf("move", "tcp://127.0.0.1:1", "straight", "1.0", "0.2"))
        assertEquals(2, r.code, "$r")
        assertTrue(r.err.contains("straight wants one number, not 2 (the speed is --speed)"), "$r")
    }

    @Test
    fun aScanWithoutABluetoothAdapterSaysSoWithoutAskingDBus() {
        assumeFalse(File("/sys/class/bluetooth/hci0").exists(), "this machine has a Bluetooth adapter")
        val run = runPocketBot(listOf("--sources", "bluetooth", "--scan-seconds", "30", "scan"))
        assertEquals(3, run.code, "$run")
        assertTrue(run.err.contains("no Bluetooth adapter hci0 on this machine"), "$run")
        assertFalse(run.err.contains("D-Bus") || run.err.contains("system bus"), "the bus is not even asked: $run")
    }

    @Test
    fun aRobotLostMidWatchEndsTheWatchWith5() = withRobots { emu, global ->
        var rows = 0
        // Five rows of the table printed: the watch runs; then the robot's emulator goes away.
        val run = runPocketBot(global + listOf("state", "PocketBot-1", "--watch", "--fields", "time.time_ms")) { line ->
            if (line.startsWith("PocketBot-1") && ++rows == 5) emu.close()
        }
        assertEquals(5, run.code, "$run")
        assertTrue(run.err.contains("lost the link to PocketBot-1"), "$run")
        assertTrue(run.out.lines().first().startsWith("ROBOT"), "$run")
    }

    @Test
    fun theEmulatorSubcommandServesRobotsThatAnotherPocketbotFinds() {
        val emulator = PocketBotProcess(listOf("emulator", "--robots", "2", "--port-base", "0", "--control-port", "0"))
        try {
            val control = emulator.awaitLine(Regex("""^control 127\.0\.0\.1:(\d+)""")).groupValues[1]
            val scan = runPocketBot(listOf("--control-port", control, "--sources", "emulator", "scan", "--json"))
            assertEquals(0, scan.code, "$scan")
            assertEquals(setOf("PocketBot-1", "PocketBot-2"), jsonLines(scan.out).map { it["name"]!!.jsonPrimitive.content }.toSet())
            emulator.send("q")
            assertEquals(0, emulator.await().code)
        } finally {
            emulator.kill()
        }
    }

    @Test
    fun theEmulatorSubcommandOnTheNetworkNamesAnAddressAnotherMachineReaches() {
        val network = NetworkInterface.getNetworkInterfaces().toList().filter { it.isUp && !it.isLoopback }
            .flatMap { it.inetAddresses.toList() }.filter { it is Inet4Address && !it.isLinkLocalAddress }.map { it.hostAddress }
        assumeTrue(network.isNotEmpty(), "this machine has no network address besides loopback: the network part cannot run here")
        val emulator = PocketBotProcess(listOf("emulator", "--robots", "1", "--port-base", "0", "--control-port", "0", "--listen", "0.0.0.0"))
        try {
            val header = emulator.awaitLine(Regex("""^PocketBot emulator: .*, on the network at .+ \(anyone there can drive these robots\)$""")).value
            val robot = emulator.awaitLine(Regex("""^robot 1 PocketBot-1 tcp ([0-9.]+):(\d+)$"""))
            val host = robot.groupValues[1]
            assertTrue(host in network, "the robot line names a network address of this machine, $host, not one of $network: $header")
            val control = emulator.awaitLine(Regex("""^control ([0-9.]+):(\d+)$"""))
            assertEquals(host, control.groupValues[1])
            // Another pocketbot, pointed at that address, finds the robot there and reads it.
            val scan = runPocketBot(listOf("--host", host, "--control-port", control.groupValues[2], "--sources", "emulator", "scan", "--json"))
            assertEquals(0, scan.code, "$scan")
            assertEquals("tcp://$host:${robot.groupValues[2]}", jsonLines(scan.out).single()["address"]!!.jsonPrimitive.content)
            val info = runPocketBot(listOf("info", "tcp://$host:${robot.groupValues[2]}", "--json"))
            assertEquals("PocketBot-1", jsonLines(info.out).single()["name"]!!.jsonPrimitive.content, "$info")
            emulator.send("q")
            assertEquals(0, emulator.await().code)
        } finally {
            emulator.kill()
        }
    }

    @Test
    fun theEmulatorSubcommandSaysWhenItCannotListen() {
        val unknown = runPocketBot(listOf("emulator", "--listen", "no-such-host.invalid"))
        assertEquals(2, unknown.code, "a listen address that names nothing is a usage error: $unknown")
        assertTrue(unknown.err.contains("no-such-host.invalid is no address of this machine"), "$unknown")
        // TEST-NET-3: an address no interface of this machine has.
        val foreign = runPocketBot(listOf("emulator", "--listen", "203.0.113.77", "--port-base", "0", "--control-port", "0"))
        assertEquals(1, foreign.code, "$foreign")
        assertTrue(foreign.err.contains("cannot listen on 203.0.113.77"), "$foreign")
    }

    @Test
    fun theEmulatorSubcommandRunsWithoutAControlPort() {
        val emulator = PocketBotProcess(listOf("emulator", "--robots", "1", "--port-base", "0", "--control-port", "-1"))
        try {
            val port = emulator.awaitLine(Regex("""^robot 1 PocketBot-1 tcp 127\.0\.0\.1:(\d+)""")).groupValues[1]
            val info = runPocketBot(listOf("info", "tcp://127.0.0.1:$port", "--json"))
            assertEquals(0, info.code, "$info")
            assertEquals("PocketBot-1", jsonLines(info.out).single()["name"]!!.jsonPrimitive.content)
            emulator.send("q")
            val run = emulator.await()
            assertEquals(0, run.code, "$run")
            assertFalse(run.out.contains("control"), "no control port: $run")
        } finally {
            emulator.kill()
        }
    }

    @Test
    fun aProgressLineGoesToATerminalAndNowhereElse() = withRobots { _, global ->
        // `script` runs the command on a pty; stdout goes to a file, so what the pty shows is stderr alone.
        val out = File("target/tty-stdout.txt").apply { delete() }
        val command = (listOf(launcher.path) + global + listOf("info", "PocketBot-1")).joinToString(" ") + " > ${out.path}"
        val script = ProcessBuilder("script", "-q", "-e", "-c", command, "/dev/null")
            .redirectInput(ProcessBuilder.Redirect.from(File("/dev/null"))).redirectErrorStream(true).start()
        val terminal = StringBuffer()
        val reader = Thread { terminal.append(script.inputStream.bufferedReader().readText()) }.apply { isDaemon = true; start() }
        if (!script.waitFor(GUARD_SECONDS, TimeUnit.SECONDS)) {
            script.destroyForcibly()
            error("pocketbot on a pty did not end: $terminal")
        }
        reader.join(10_000)
        assertEquals(0, script.exitValue(), "$terminal")
        assertTrue(terminal.contains("\r\u001b[Kconnecting 1/1"), "a progress line on the terminal: ${terminal.toString().replace("\u001b", "ESC")}")
        assertTrue(out.readText().startsWith("NAME"), "the result on stdout, without progress")
        assertFalse(out.readText().contains("connecting"), "no progress in stdout")

        val piped = runPocketBot(global + listOf("info", "PocketBot-1"))
        assertEquals(0, piped.code, "$piped")
        assertEquals("", piped.err, "no progress line when stderr is not a terminal")
    }
}
