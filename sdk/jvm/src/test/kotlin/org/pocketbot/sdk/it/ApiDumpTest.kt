package org.pocketbot.sdk.it

import org.jetbrains.kotlin.abi.tools.AbiFilters
import org.jetbrains.kotlin.abi.tools.AbiTools
import org.junit.jupiter.api.Test
import org.pocketbot.emulator.Emulator
import org.pocketbot.protocol.ProtocolInfo
import org.pocketbot.sdk.Robot
import org.pocketbot.sdk.transport.TcpTransport
import java.io.File
import java.util.zip.ZipFile
import kotlin.test.assertEquals
import kotlin.test.fail

/**
 * The public API of every published library is checked in beside it: `sdk/core/api/pocketbot-sdk-core.api`,
 * `sdk/jvm/api/pocketbot-sdk-jvm.api`, `sdk/protocol/api/pocketbot-protocol.api` (the wire layer, generated from the
 * schema; the state model and enums users read are generated from the same schema into sdk-core, so a schema change
 * shows in review as a change of these dumps), `emulator/api/pocketbot-emulator.api` and `emulator/simulated/api/pocketbot-emulator-simulated.api`,
 * dumped by the Kotlin toolchain's own ABI tools from the compiled classes and their Kotlin metadata (the format of
 * kotlinx binary-compatibility-validator, which kotlinx.coroutines and Kable keep). `internal` declarations,
 * whatever their JVM visibility, never show. The compatibility policy (docs/compatibility.md) is stated in terms of
 * these files. A change to the public surface fails this test until the dump is updated on purpose:
 *
 *     mvn -B -pl sdk/jvm -am test -Dtest=ApiDumpTest -Dsurefire.failIfNoSpecifiedTests=false -Dpocketbot.api.update=true
 *
 * and the diff of the .api files is reviewed with the change.
 */
class ApiDumpTest {
    @Test
    fun sdkCoreApiMatchesTheCheckedInDump() = check(Robot::class.java, File("../core/api/pocketbot-sdk-core.api"))

    @Test
    fun protocolApiMatchesTheCheckedInDump() = check(ProtocolInfo::class.java, File("../protocol/api/pocketbot-protocol.api"))

    @Test
    fun sdkJvmApiMatchesTheCheckedInDump() = check(TcpTransport::class.java, File("api/pocketbot-sdk-jvm.api"))

    /** Without the firmware compiled to bytecode: its classes are public for Chicory, and change with every build. */
    @Test
    fun emulatorApiMatchesTheCheckedInDump() = check(
        Emulator::class.java, File("../../emulator/api/pocketbot-emulator.api"),
        AbiFilters(emptySet(), setOf("org.pocketbot.emulator.firmware.FirmwareModule**", "org.pocketbot.emulator.firmware.HciFirmwareModule**"), emptySet(), emptySet()),
    )

    @Test
    fun emulatorSimulatedApiMatchesTheCheckedInDump() = check(
        Class.forName("org.pocketbot.emulator.SimulationKt"), File("../../emulator/simulated/api/pocketbot-emulator-simulated.api"),
    )

    private fun check(anyClass: Class<*>, dumpFile: File, filters: AbiFilters = AbiFilters.EMPTY) {
        val actual = dump(anyClass, filters)
        val update = System.getProperty("pocketbot.api.update") == "true" || System.getenv("POCKETBOT_API_UPDATE") == "1"
        if (update) {
            dumpFile.parentFile.mkdirs()
            dumpFile.writeText(actual)
            println("API dump written to ${dumpFile.canonicalPath}")
            return
        }
        if (!dumpFile.exists()) fail("no API dump at ${dumpFile.canonicalPath}; create it with -Dpocketbot.api.update=true")
        val expected = dumpFile.readText()
        if (expected != actual) {
            val removed = expected.lines().filter { it !in actual.lines() && it.isNotBlank() }
            val added = actual.lines().filter { it !in expected.lines() && it.isNotBlank() }
            assertEquals(
                expected, actual,
                "the public API in ${dumpFile.name} changed (removed ${removed.size}, added ${added.size} lines):\n" +
                    removed.take(20).joinToString("") { "- $it\n" } + added.take(20).joinToString("") { "+ $it\n" } +
                    "If intended, update the dump with -Dpocketbot.api.update=true",
            )
        }
    }

    /** The ABI dump of the module [anyClass] was compiled in, from its classes directory or jar. */
    private fun dump(anyClass: Class<*>, filters: AbiFilters): String {
        val location = File(anyClass.protectionDomain.codeSource.location.toURI())
        val work = File("target/api-dump/${location.nameWithoutExtension}").apply { deleteRecursively(); mkdirs() }
        val classes = if (location.isDirectory) {
            location.walkTopDown().filter { it.isFile && it.name.endsWith(".class") }.toList()
        } else {
            ZipFile(location).use { zip ->
                zip.entries().asSequence().filter { it.name.endsWith(".class") && !it.name.startsWith("META-INF") }.map { e ->
                    File(work, e.name).apply { parentFile.mkdirs(); writeBytes(zip.getInputStream(e).readBytes()) }
                }.toList()
            }
        }
        return StringBuilder().also { AbiTools.getInstance().printJvmDump(it, classes, filters) }.toString()
    }
}
