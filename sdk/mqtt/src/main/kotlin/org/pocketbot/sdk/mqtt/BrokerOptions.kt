package org.pocketbot.sdk.mqtt

import java.io.File
import java.net.URI
import java.net.URISyntaxException
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds

/**
 * How to reach an MQTT broker: `mqtt://host[:1883]` (plain) or `mqtts://host[:8883]` (TLS), with the credentials
 * the broker's password file knows, made by a builder so that a new option never breaks a caller:
 *
 * ```
 * val options = BrokerOptions("mqtts://broker.lab:8883") {
 *     username = "alice"
 *     passwordFrom(null) // POCKETBOT_BROKER_PASSWORD
 *     trustedCertificates = File("ca.crt")
 * }
 * ```
 *
 * Immutable; [toString] never shows the password.
 */
public class BrokerOptions private constructor(
    /** The broker as given: `mqtt://host:port` or `mqtts://host:port`. */
    public val url: String,
    b: Builder,
) {
    /** The MQTT username, or null to connect without one (a broker with the shipped configuration refuses that). */
    public val username: String? = b.username

    internal val password: CharArray? = b.password?.copyOf()

    /** The PEM file of the certificate authorities trusted for `mqtts`; null trusts the JVM's own trust store. */
    public val trustedCertificates: File? = b.trustedCertificates

    /** The MQTT client identifier; null draws a random one at each connect. */
    public val clientId: String? = b.clientId

    /**
     * A down frame older than this when it reaches the gateway is dropped, not executed late; it is also the MQTT 5
     * message expiry of down messages, rounded up to whole seconds, so a stalled broker drops them itself.
     */
    public val maxFrameAge: Duration = b.maxFrameAge

    /**
     * Gateways only: how long state and debug frames may wait to share one up message with the frames that follow.
     * Any other frame (acks, errors, answers) sends its message at once, so command to ack is never delayed.
     */
    public val upBatchWindow: Duration = b.upBatchWindow

    /**
     * Clients only: the sessions of this user only watch robots (they publish to `watch`, not `down`), as a broker
     * user allowed only to watch must. The robot then refuses every command that would move it.
     */
    public val watchOnly: Boolean = b.watchOnly

    /** The broker's host name or address. */
    internal val host: String

    /** The broker's port. */
    internal val port: Int

    /** True for `mqtts`. */
    internal val tls: Boolean

    init {
        val uri = try {
            URI(url)
        } catch (e: URISyntaxException) {
            throw IllegalArgumentException("broker URL \"$url\" is not a URL: ${e.reason}", e)
        }
        tls = when (uri.scheme?.lowercase()) {
            "mqtt" -> false
            "mqtts" -> true
            null -> throw IllegalArgumentException("broker URL \"$url\" has no scheme: write mqtt://host or mqtts://host")
            else -> throw IllegalArgumentException("broker URL \"$url\": scheme ${uri.scheme} is not mqtt or mqtts")
        }
        host = uri.host?.removePrefix("[")?.removeSuffix("]") ?: throw IllegalArgumentException("broker URL \"$url\" has no host")
        port = if (uri.port == -1) (if (tls) DEFAULT_TLS_PORT else DEFAULT_PORT) else uri.port
        require(port in 1..65535) { "broker URL \"$url\": port $port is not a TCP port" }
        require(uri.userInfo == null) { "broker URL \"$url\": give the username and password as options, not in the URL" }
        require(uri.rawPath.isNullOrEmpty() || uri.rawPath == "/") { "broker URL \"$url\" has a path; write mqtt://host:port" }
        require(uri.rawQuery == null && uri.rawFragment == null) { "broker URL \"$url\" has a query or fragment" }
        require(maxFrameAge.isPositive()) { "maxFrameAge must be positive, was $maxFrameAge" }
        require(!upBatchWindow.isNegative()) { "upBatchWindow must not be negative, was $upBatchWindow" }
        require(clientId == null || clientId.isNotEmpty() && clientId.none { it in "/+#" }) {
            "clientId \"$clientId\" must be non-empty, without '/', '+' or '#'"
        }
        require(trustedCertificates == null || tls) { "trustedCertificates are for mqtts:// brokers; \"$url\" is plain mqtt" }
    }

    /** The broker's `host:port`, as robots' addresses show it. */
    internal val hostPort: String get() = if (':' in host) "[$host]:$port" else "$host:$port"

    override fun toString(): String =
        "BrokerOptions($url, username=$username${if (password != null) ", password=***" else ""}" +
            "${trustedCertificates?.let { ", trustedCertificates=$it" } ?: ""}, maxFrameAge=$maxFrameAge)"

    /** The options' values while [BrokerOptions] builds them; every property starts at its default. */
    public class Builder internal constructor() {
        /** See [BrokerOptions.username]. */
        public var username: String? = null

        /** The password for [username]; copied when the options are built. */
        public var password: CharArray? = null

        /** See [BrokerOptions.trustedCertificates]. */
        public var trustedCertificates: File? = null

        /** See [BrokerOptions.clientId]. */
        public var clientId: String? = null

        /** See [BrokerOptions.maxFrameAge]. */
        public var maxFrameAge: Duration = 500.milliseconds

        /** See [BrokerOptions.upBatchWindow]. */
        public var upBatchWindow: Duration = 10.milliseconds

        /** See [BrokerOptions.watchOnly]. */
        public var watchOnly: Boolean = false

        /**
         * Sets [password] as PocketBot's programs take one: the first line of [file], else the environment variable
         * [PASSWORD_VARIABLE] when it is set and not empty, else none. Never from a command line, where every user of
         * the machine reads it (`ps`).
         */
        public fun passwordFrom(file: File?) {
            password = (file?.useLines { it.firstOrNull() } ?: System.getenv(PASSWORD_VARIABLE)?.takeIf { it.isNotEmpty() })?.toCharArray()
        }

        internal fun build(url: String) = BrokerOptions(url, this)
    }

    public companion object {
        /** The port of `mqtt://` when the URL gives none. */
        public const val DEFAULT_PORT: Int = 1883

        /** The port of `mqtts://` when the URL gives none. */
        public const val DEFAULT_TLS_PORT: Int = 8883

        /** The environment variable [Builder.passwordFrom] reads a password from when no file is given. */
        public const val PASSWORD_VARIABLE: String = "POCKETBOT_BROKER_PASSWORD"
    }
}

/**
 * Options for the broker at [url] (`mqtt://host[:port]` or `mqtts://host[:port]`), changed by [build]. Throws
 * [IllegalArgumentException] saying what is wrong with the URL or an option.
 */
public fun BrokerOptions(url: String, build: BrokerOptions.Builder.() -> Unit = {}): BrokerOptions =
    BrokerOptions.Builder().apply(build).build(url)
