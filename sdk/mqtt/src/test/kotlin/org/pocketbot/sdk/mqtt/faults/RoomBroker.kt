package org.pocketbot.sdk.mqtt.faults

import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import java.io.File

/**
 * Starts a room broker (the shipped configuration) bridged to [central] with the shipped deploy/mosquitto/bridge.conf
 * as it is, but for the central broker's address (loopback, [centralPort]: its TLS port, or a [CutProxy] in front of
 * it), the bridge user's password and the CA that signed the central broker's certificate.
 */
fun startRoomBroker(central: MosquittoBroker, centralPort: Int = central.tlsPort): MosquittoBroker {
    val replaced = mutableSetOf<String>()
    val bridge = File(MosquittoBroker.deployDir, "bridge.conf").readLines().map { line ->
        val key = line.substringBefore(' ')
        when (key) {
            "address" -> "address 127.0.0.1:$centralPort"
            "remote_password" -> "remote_password ${central.password("bridge")}"
            "bridge_cafile" -> "bridge_cafile ${central.caFile.path}"
            else -> return@map line
        }.also { replaced += key }
    }
    check(replaced == setOf("address", "remote_password", "bridge_cafile")) {
        "deploy/mosquitto/bridge.conf changed: replaced ${replaced.sorted()}, expected address, remote_password, bridge_cafile"
    }
    return MosquittoBroker.start(extraConfig = bridge)
}
