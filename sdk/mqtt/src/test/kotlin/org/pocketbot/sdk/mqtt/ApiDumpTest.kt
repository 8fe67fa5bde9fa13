package org.pocketbot.sdk.mqtt

import org.jetbrains.kotlin.abi.tools.AbiFilters
import org.jetbrains.kotlin.abi.tools.AbiTools
import org.junit.jupiter.api.Test
import java.io.File
import kotlin.test.assertEquals
import kotlin.test.fail

/**
 * The public API of pocketbot-sdk-mqtt is checked in beside it, `sdk/mqtt/api/pocketbot-sdk-mqtt.api`, dumped by the
 * Kotlin toolchain's ABI tools as sdk/jvm's ApiDumpTest dumps the other libraries (docs/compatibility.md). A change
 * to the public surface fails this test until the dump is updated on purpose:
 *
 *     mvn -B -pl sdk/mqtt -am test -Dtest=ApiDumpTest -Dsurefire.failIfNoSpecifiedTests=false -Dpocketbot.api.update=true
 */
class ApiDumpTest {
    @Test
    fun sdkMqttApiMatchesTheCheckedInDump() {
        val dumpFile = File("api/pocketbot-sdk-mqtt.api")
        val location = File(BrokerClient::class.java.protectionDomain.codeSource.location.toURI())
        val classes = location.walkTopDown().filter { it.isFile && it.name.endsWith(".class") }.toList()
        val actual = StringBuilder().also { AbiTools.getInstance().printJvmDump(it, classes, AbiFilters.EMPTY) }.toString()
        if (System.getProperty("pocketbot.api.update") == "true" || System.getenv("POCKETBOT_API_UPDATE") == "1") {
            dumpFile.writeText(actual)
            println("API dump written to ${dumpFile.canonicalPath}")
            return
        }
        if (!dumpFile.exists()) fail("no API dump at ${dumpFile.canonicalPath}; create it with -Dpocketbot.api.update=true")
        assertEquals(dumpFile.readText(), actual, "the public API in ${dumpFile.name} changed; if intended, update the dump with -Dpocketbot.api.update=true")
    }
}
