package org.pocketbot.sdk.jvm

/** Placeholder proving the sdk-jvm build; remove once real transports exist. */
internal object JvmBuildProbe {
    fun describe(host: String, port: Int): String {
        require(port in 1..65535) { "port out of range: $port" }
        return "tcp://$host:$port"
    }
}
