package org.pocketbot.sdk.mqtt

import com.hivemq.client.mqtt.MqttClient
import com.hivemq.client.mqtt.MqttGlobalPublishFilter
import com.hivemq.client.mqtt.datatypes.MqttQos
import com.hivemq.client.mqtt.mqtt5.Mqtt5BlockingClient
import com.hivemq.client.mqtt.mqtt5.exceptions.Mqtt5PubAckException
import com.hivemq.client.mqtt.mqtt5.message.publish.Mqtt5PublishResult
import com.hivemq.client.mqtt.mqtt5.message.publish.puback.Mqtt5PubAckReasonCode
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.flow.first
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.junit.jupiter.api.AfterAll
import org.junit.jupiter.api.BeforeAll
import org.junit.jupiter.api.Test
import org.junit.jupiter.api.TestInstance
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.Speed
import org.pocketbot.protocol.Frames
import org.pocketbot.protocol.Heartbeat
import org.pocketbot.protocol.HostRole
import org.pocketbot.protocol.MoveStraight
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SetRole
import org.pocketbot.sdk.Movement
import org.pocketbot.sdk.MovementOutcome
import org.pocketbot.sdk.connect
import org.pocketbot.sdk.mqtt.internal.Wire
import org.pocketbot.sdk.mqtt.internal.monotonicMs
import org.pocketbot.sdk.mqtt.testing.MosquittoBroker
import java.util.concurrent.TimeUnit
import kotlin.random.Random
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.seconds

/**
 * The shipped broker configuration and the gateway keep robots safe: unknown and anonymous clients get nothing, a
 * watcher cannot move a robot, a driver cannot write where it has no business, and whatever arrives on the gateway's
 * topics that is not a well-formed, timely message of a served robot is dropped and counted while robots keep working.
 * The hostile clients here are raw MQTT clients, not the SDK: they send what the SDK never would.
 */
@TestInstance(TestInstance.Lifecycle.PER_CLASS)
class MqttSecurityTest {
    private lateinit var broker: MosquittoBroker
    private val emulator = Emulator.local(robots = 1, world = "straight")
    private val scope = CoroutineScope(SupervisorJob() + Dispatchers.Default)
    private lateinit var gateway: Gateway
    private val robotId get() = gateway.robots.value.single()
    private val raws = ArrayList<Mqtt5BlockingClient>()

    @BeforeAll
    fun start() = runBlocking<Unit> {
        broker = MosquittoBroker.start()
        emulator.start(Speed.Realtime(1.0))
        gateway = scope.startGateway("lab1", broker.options("lab1"), emulator.discoverer())
        withTimeout(5.seconds) { gateway.robots.first { it.size == 1 } }
    }

    @AfterAll
    fun stop() = runBlocking<Unit> {
        raws.forEach { runCatching { it.disconnect() } }
        gateway.close()
        scope.cancel()
        emulator.close()
        broker.close()
    }

    @Test
    fun anonymousUnknownAndWrongPasswordClientsAreRefusedAtConnect() = runBlocking<Unit> {
        val anonymous = assertFailsWith<BrokerException> { connectBroker(broker.options(null)) }
        assertTrue("not authorised" in anonymous.message!!, anonymous.message)
        val wrong = assertFailsWith<BrokerException> { connectBroker(broker.options("alice") { password = "guess".toCharArray() }) }
        assertTrue("bad username or password" in wrong.message!! || "not authorised" in wrong.message!!, wrong.message)
        val stranger = assertFailsWith<BrokerException> { connectBroker(BrokerOptions(broker.url) { username = "mallory"; password = "x".toCharArray(); trustedCertificates = broker.caFile }) }
        assertTrue("refused" in stranger.message!!, stranger.message)
        val untrusted = assertFailsWith<BrokerException> { connectBroker(broker.options("alice") { trustedCertificates = null }) }
        assertTrue("TLS" in untrusted.message!!, untrusted.message)
        val nobody = assertFailsWith<BrokerException> { connectBroker(BrokerOptions("mqtt://127.0.0.1:${MosquittoBroker.freePort()}")) }
        assertTrue("unreachable" in nobody.message!!, nobody.message)
    }

    @Test
    fun aWatcherCannotMoveARobot() = runBlocking<Unit> {
        val truth = emulator.robots.single()
        val before = truth.trueWheelDistances
        val stats = gateway.stats.value
        val bob = raw("bob")
        val moves = listOf(Frames.encode(SetRole(HostRole.DRIVE.code, "bob"), 1), Frames.encode(MoveStraight(7, 0.2f, 0.2f), 2))

        // On down, the broker refuses him: nothing reaches the gateway.
        val down = "pb/v1/lab1/$robotId/down/bob/b1"
        assertRefused(publish(bob, down, Wire.text(Wire.OPEN, monotonicMs(), "raw-bob")))
        assertRefused(publish(bob, down, Wire.frames(monotonicMs(), moves)))

        // On watch, the gateway passes a watcher's reads and drops what would take the drive or move the robot.
        val watch = "pb/v1/lab1/$robotId/watch/bob/b2"
        publish(bob, watch, Wire.text(Wire.OPEN, monotonicMs(), "raw-bob"))
        publish(bob, watch, Wire.frames(monotonicMs(), moves + Frames.encode(ReadSettings, 3)))
        withTimeout(5.seconds) { gateway.stats.first { it.droppedNotAllowed == stats.droppedNotAllowed + 2 } }
        assertEquals(stats.framesDown + 1, gateway.stats.value.framesDown, "the read passed")
        delay(1000)
        val after = truth.trueWheelDistances
        assertEquals(before.leftM, after.leftM, 1e-4, "the robot did not move")
        assertEquals(before.rightM, after.rightM, 1e-4, "the robot did not move")
    }

    @Test
    fun aDriverCannotWriteIntoAnotherUsersOrAGatewaysTopics() = runBlocking<Unit> {
        val alice = raw("alice")
        for (topic in listOf(
            "pb/v1/lab1/status", "pb/v1/lab1/$robotId/info", "pb/v1/lab1/$robotId/lease",
            "pb/v1/lab1/$robotId/up/bob/x", "pb/v1/lab1/$robotId/down/bob/x", "pb/v1/lab1/$robotId/watch/bob/x",
            "pb/v1/clients/bob/x",
        )) assertRefused(publish(alice, topic, """{"online":false}""".encodeToByteArray()), topic)
        // Mosquitto grants any subscription and delivers only what the reader's ACL allows: alice sees none of bob's.
        alice.publishes(MqttGlobalPublishFilter.ALL).use { aliceSees ->
            alice.subscribeWith().topicFilter("pb/v1/lab1/+/up/#").send()
            val bob = raw("bob")
            bob.publishes(MqttGlobalPublishFilter.ALL).use { bobSees ->
                bob.subscribeWith().topicFilter("pb/v1/lab1/+/up/bob/#").send()
                publish(bob, "pb/v1/lab1/$robotId/watch/bob/b3", Wire.text(Wire.OPEN, monotonicMs(), "raw-bob"))
                val answer = bobSees.receive(5, TimeUnit.SECONDS)
                assertEquals("pb/v1/lab1/$robotId/up/bob/b3", answer.orElse(null)?.topic?.toString(), "the gateway answers bob")
                val seen = generateSequence { aliceSees.receive(1, TimeUnit.SECONDS).orElse(null) }.map { it.topic.toString() }.toList()
                assertTrue(seen.none { "/up/bob/" in it }, "alice must not read bob's session: $seen")
            }
        }
        val client = connectBroker(broker.options("alice"))
        withTimeout(5.seconds) { client.gateways.first { it["lab1"]?.online == true } }
        client.close()
    }

    @Test
    fun garbageOversizeWrongTopicsAndLateFramesAreDroppedAndCountedWhileARobotKeepsWorking() = runBlocking<Unit> {
        val client = connectBroker(broker.options("alice"))
        val truth = emulator.robots.single()
        val robot = client.device("lab1", robotId).connect(this)
        val before = truth.trueWheelDistances
        val stats = gateway.stats.value
        val movement = robot.locomotion.enqueue(Movement.Straight(0.3, 0.2))

        val mallory = raw("alice")
        val session = "pb/v1/lab1/$robotId/down/alice/hostile"
        val random = Random(23)
        val garbage = listOf(
            ByteArray(0), random.nextBytes(1), random.nextBytes(9), random.nextBytes(200),
            byteArrayOf(9) + ByteArray(20),                                  // an unknown version
            byteArrayOf(Wire.VERSION.toByte(), 7) + ByteArray(8),            // an unknown kind
            Wire.frames(monotonicMs(), listOf(Frames.encode(Heartbeat, 1))).let { it.copyOf(it.size - 1) },  // cut short
        )
        garbage.forEach { publish(mallory, session, it) }
        val tooLongFrame = ByteArray(Frames.MAX_FRAME + 1)
        publish(mallory, session, Wire.frames(monotonicMs(), listOf(tooLongFrame)))
        publish(mallory, session, ByteArray(Wire.MAX_DOWN_MESSAGE + 1))
        val heartbeat = Wire.frames(monotonicMs(), listOf(Frames.encode(Heartbeat, 1)))
        for (topic in listOf("pb/v1/lab1/nosuch/down/alice/s", "pb/v1/lab1/$robotId/down/alice", "pb/v1/lab1/$robotId/down/alice/s/extra"))
            publish(mallory, topic, heartbeat)
        // A session whose second message took 2 s longer than its first: late, dropped.
        val late = "pb/v1/lab1/$robotId/down/alice/late"
        publish(mallory, late, Wire.text(Wire.OPEN, monotonicMs(), "raw-alice"))
        publish(mallory, late, Wire.frames(monotonicMs() - 2000, listOf(Frames.encode(Heartbeat, 1))))

        withTimeout(5.seconds) {
            gateway.stats.first {
                it.droppedGarbage == stats.droppedGarbage + garbage.size && it.droppedOversize == stats.droppedOversize + 2 &&
                    it.droppedUnknownRobot == stats.droppedUnknownRobot + 3 && it.droppedLate == stats.droppedLate + 1
            }
        }
        val result = movement.await()
        assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
        val after = truth.trueWheelDistances
        assertEquals(0.3, (after.leftM - before.leftM + after.rightM - before.rightM) / 2, 0.01, "ground truth")
        robot.disconnect()
        client.close()
    }

    @Test
    fun garbageFromABrokenGatewayIsCountedByTheClientsLinkWhileTheRobotKeepsWorking() = runBlocking<Unit> {
        val client = connectBroker(broker.options("alice"))
        val robot = client.device("lab1", robotId).connect(this)
        // The session's up topic, as the broker delivers it to alice (a second client of hers listens in).
        val listener = raw("alice")
        val upTopic = listener.publishes(MqttGlobalPublishFilter.ALL).use { publishes ->
            listener.subscribeWith().topicFilter("pb/v1/lab1/$robotId/up/alice/#").send()
            publishes.receive(5, TimeUnit.SECONDS).orElseThrow().topic.toString()
        }
        val brokenGateway = raw("lab1")
        val before = robot.linkStats.value
        publish(brokenGateway, upTopic, byteArrayOf(9, 9, 9))
        publish(brokenGateway, upTopic, Wire.frames(monotonicMs(), listOf(ByteArray(Frames.MAX_FRAME + 1))))
        withTimeout(5.seconds) {
            robot.linkStats.first { it.badFraming == before.badFraming + 1 && it.tooLong == before.tooLong + 1 }
        }
        val result = robot.locomotion.enqueue(Movement.Straight(0.05, 0.2)).await()
        assertEquals(MovementOutcome.FINISHED, result.outcome, "$result")
        robot.disconnect()
        client.close()
    }

    /** A raw MQTT client of [user] on the plain listener (the same passwords and ACL as TLS). */
    private fun raw(user: String): Mqtt5BlockingClient = MqttClient.builder().useMqttVersion5()
        .identifier("raw-$user-${raws.size}").serverHost("127.0.0.1").serverPort(broker.plainPort)
        .simpleAuth().username(user).password(broker.password(user).encodeToByteArray()).applySimpleAuth()
        .buildBlocking().also { it.connect(); raws += it }

    /** Publishes at QoS 1 and returns the broker's answer. */
    private fun publish(client: Mqtt5BlockingClient, topic: String, payload: ByteArray): Mqtt5PubAckReasonCode = try {
        (client.publishWith().topic(topic).qos(MqttQos.AT_LEAST_ONCE).payload(payload).send() as Mqtt5PublishResult.Mqtt5Qos1Result).pubAck.reasonCode
    } catch (e: Mqtt5PubAckException) {
        e.mqttMessage.reasonCode
    }

    private fun assertRefused(code: Mqtt5PubAckReasonCode, what: String = "") =
        assertEquals(Mqtt5PubAckReasonCode.NOT_AUTHORIZED, code, "$what: the broker must refuse it")
}
