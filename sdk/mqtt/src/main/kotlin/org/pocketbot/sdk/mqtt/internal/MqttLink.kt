package org.pocketbot.sdk.mqtt.internal

import com.hivemq.client.mqtt.MqttClient
import com.hivemq.client.mqtt.MqttGlobalPublishFilter
import com.hivemq.client.mqtt.datatypes.MqttQos
import com.hivemq.client.mqtt.exceptions.ConnectionFailedException
import com.hivemq.client.mqtt.lifecycle.MqttDisconnectSource
import com.hivemq.client.mqtt.mqtt5.Mqtt5AsyncClient
import com.hivemq.client.mqtt.mqtt5.exceptions.Mqtt5ConnAckException
import com.hivemq.client.mqtt.mqtt5.message.connect.connack.Mqtt5ConnAckReasonCode
import com.hivemq.client.mqtt.mqtt5.message.publish.Mqtt5Publish
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.future.await
import kotlinx.coroutines.withTimeoutOrNull
import org.pocketbot.sdk.mqtt.BrokerException
import org.pocketbot.sdk.mqtt.BrokerOptions
import java.io.IOException
import java.security.GeneralSecurityException
import java.security.KeyStore
import java.security.cert.CertificateFactory
import java.util.concurrent.CompletionException
import java.util.concurrent.TimeUnit
import javax.net.ssl.SSLException
import javax.net.ssl.TrustManagerFactory
import kotlin.time.Duration.Companion.seconds

/**
 * One MQTT 5 connection to the broker of [options], shared by everything a [org.pocketbot.sdk.mqtt.BrokerClient] or a
 * [org.pocketbot.sdk.mqtt.Gateway] does: HiveMQ's asynchronous client with its automatic reconnect, a last will, and
 * one callback for every message received ([onMessage], called on the client's Netty thread: it must not block).
 * Once connected, it reconnects by itself until [disconnect]; [onConnected] runs after each (re)connect.
 */
internal class MqttLink(
    val options: BrokerOptions,
    val clientId: String,
    willTopic: String,
    willPayload: ByteArray,
    willRetain: Boolean,
    private val onConnected: () -> Unit,
    private val onDisconnected: (reason: String) -> Unit,
    onMessage: (Mqtt5Publish) -> Unit,
) {
    private val _connected = MutableStateFlow(false)
    val connected: StateFlow<Boolean> = _connected.asStateFlow()

    @Volatile private var everConnected = false
    @Volatile private var closing = false

    /** MQTT 5 message expiry of down messages: maxFrameAge rounded up to whole seconds. */
    val expirySeconds: Long = ((options.maxFrameAge.inWholeMilliseconds + 999) / 1000).coerceAtLeast(1)

    val client: Mqtt5AsyncClient = MqttClient.builder().useMqttVersion5()
        .identifier(clientId)
        .serverHost(options.host)
        .serverPort(options.port)
        .apply { if (options.tls) sslConfig(sslConfig(options)) }
        .apply {
            if (options.username != null) {
                simpleAuth().username(options.username).apply {
                    options.password?.let { password(String(it).encodeToByteArray()) }
                }.applySimpleAuth()
            }
        }
        .willPublish().topic(willTopic).payload(willPayload).qos(MqttQos.AT_LEAST_ONCE).retain(willRetain).applyWillPublish()
        .automaticReconnect().initialDelay(RECONNECT_INITIAL_MS, TimeUnit.MILLISECONDS)
        .maxDelay(RECONNECT_MAX_MS, TimeUnit.MILLISECONDS).applyAutomaticReconnect()
        .addConnectedListener {
            everConnected = true
            _connected.value = true
            onConnected()
        }
        .addDisconnectedListener { context ->
            val wasConnected = _connected.value
            _connected.value = false
            // A first connect that failed is reported by connect(), and not tried again; neither is a closed link.
            if (!everConnected || closing || context.source == MqttDisconnectSource.USER) context.reconnector.reconnect(false)
            if (wasConnected) onDisconnected(describe(context.cause))
        }
        .buildAsync()
        .also { it.publishes(MqttGlobalPublishFilter.ALL, onMessage) }

    /** Connects the first time; throws [BrokerException] saying why it failed. */
    suspend fun connect() {
        try {
            client.connectWith().cleanStart(true).keepAlive(KEEP_ALIVE_SECONDS).send().await()
        } catch (e: Throwable) {
            val cause = if (e is CompletionException) e.cause ?: e else e
            throw BrokerException("cannot connect to ${options.url} as ${options.username ?: "anonymous"}: ${describe(cause)}", cause)
        }
    }

    /** Subscribes to [filters] at QoS 1 (retained presence) and waits for the broker's answer. */
    suspend fun subscribe(filters: List<String>) {
        for (filter in filters) client.subscribeWith().topicFilter(filter).qos(MqttQos.AT_LEAST_ONCE).send().await()
    }

    /** Publishes without waiting (a failure while the connection is down is the reconnect's business). */
    fun publish(topic: String, payload: ByteArray, qos: MqttQos = MqttQos.AT_MOST_ONCE, retain: Boolean = false, expirySeconds: Long? = null) {
        client.publishWith().topic(topic).payload(payload).qos(qos).retain(retain)
            .apply { if (expirySeconds != null) messageExpiryInterval(expirySeconds) }
            .send()
    }

    /** Publishes and waits until the broker has it (QoS 1) or it is written (QoS 0). */
    suspend fun publishAndWait(topic: String, payload: ByteArray, qos: MqttQos = MqttQos.AT_LEAST_ONCE, retain: Boolean = false) {
        client.publishWith().topic(topic).payload(payload).qos(qos).retain(retain).send().await()
    }

    /** Disconnects for good; no reconnect follows. */
    suspend fun disconnect() {
        closing = true
        try {
            withTimeoutOrNull(DISCONNECT_TIMEOUT) { client.disconnect().await() }
        } catch (e: Exception) {
            // already disconnected, or the broker is gone: either way the link is down
        }
        _connected.value = false
    }

    companion object {
        const val KEEP_ALIVE_SECONDS = 10
        const val RECONNECT_INITIAL_MS = 200L
        const val RECONNECT_MAX_MS = 5_000L
        val DISCONNECT_TIMEOUT = 2.seconds

        /** A sentence for people saying why a connection failed or ended. */
        fun describe(cause: Throwable?): String {
            var e = cause
            while (e != null) {
                when {
                    e is Mqtt5ConnAckException -> return when (e.mqttMessage.reasonCode) {
                        Mqtt5ConnAckReasonCode.NOT_AUTHORIZED -> "refused: not authorised"
                        Mqtt5ConnAckReasonCode.BAD_USER_NAME_OR_PASSWORD -> "refused: bad username or password"
                        else -> "refused: ${e.mqttMessage.reasonCode.name.lowercase().replace('_', ' ')}"
                    }
                    e is SSLException -> return "TLS failed: ${e.message}"
                    e is java.net.ConnectException -> return "unreachable: ${e.message}"
                    e is ConnectionFailedException && e.cause == null -> return "unreachable: ${e.message}"
                }
                e = e.cause
            }
            return cause?.message ?: cause?.let { it::class.simpleName } ?: "connection closed"
        }

        private fun sslConfig(options: BrokerOptions) = com.hivemq.client.mqtt.MqttClientSslConfig.builder().apply {
            options.trustedCertificates?.let { trustManagerFactory(trustManagers(it)) }
        }.build()

        private fun trustManagers(pem: java.io.File): TrustManagerFactory = try {
            val certificates = pem.inputStream().use { CertificateFactory.getInstance("X.509").generateCertificates(it) }
            require(certificates.isNotEmpty()) { "no certificate in $pem" }
            val store = KeyStore.getInstance(KeyStore.getDefaultType()).apply { load(null, null) }
            certificates.forEachIndexed { i, c -> store.setCertificateEntry("ca$i", c) }
            TrustManagerFactory.getInstance(TrustManagerFactory.getDefaultAlgorithm()).apply { init(store) }
        } catch (e: IOException) {
            throw BrokerException("cannot read the trusted certificates $pem: ${e.message}", e)
        } catch (e: GeneralSecurityException) {
            throw BrokerException("the trusted certificates $pem are not PEM certificates: ${e.message}", e)
        }
    }
}

/** A random id of [bytes] bytes in hex: session ids and client ids. */
internal fun randomHex(bytes: Int): String {
    val b = ByteArray(bytes).also { java.security.SecureRandom().nextBytes(it) }
    return b.joinToString("") { "%02x".format(it) }
}
