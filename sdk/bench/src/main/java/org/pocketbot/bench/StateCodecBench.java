package org.pocketbot.bench;

import java.nio.ByteBuffer;
import java.nio.ByteOrder;
import java.util.Arrays;
import java.util.concurrent.TimeUnit;

import javolution.io.Struct;
import org.openjdk.jmh.annotations.Benchmark;
import org.openjdk.jmh.annotations.BenchmarkMode;
import org.openjdk.jmh.annotations.Fork;
import org.openjdk.jmh.annotations.Measurement;
import org.openjdk.jmh.annotations.Mode;
import org.openjdk.jmh.annotations.OutputTimeUnit;
import org.openjdk.jmh.annotations.Scope;
import org.openjdk.jmh.annotations.Setup;
import org.openjdk.jmh.annotations.State;
import org.openjdk.jmh.annotations.Warmup;
import org.openjdk.jmh.infra.Blackhole;
import org.pocketbot.protocol.Colour;
import org.pocketbot.protocol.Crc16;
import org.pocketbot.protocol.DistanceClass;
import org.pocketbot.protocol.FrameResult;
import org.pocketbot.protocol.Frames;
import org.pocketbot.protocol.IrLed;
import org.pocketbot.protocol.LineFollowStatus;
import org.pocketbot.protocol.LocoMode;
import org.pocketbot.protocol.Packet;
import org.pocketbot.protocol.ProximitySide;
import org.pocketbot.protocol.RobotState;
import org.pocketbot.protocol.StateAccel;
import org.pocketbot.protocol.StateColour;
import org.pocketbot.protocol.StateEncoders;
import org.pocketbot.protocol.StateErrors;
import org.pocketbot.protocol.StateFull;
import org.pocketbot.protocol.StateIndicators;
import org.pocketbot.protocol.StateLine;
import org.pocketbot.protocol.StateLineFollow;
import org.pocketbot.protocol.StateLocomotion;
import org.pocketbot.protocol.StatePower;
import org.pocketbot.protocol.StateProximity;
import org.pocketbot.protocol.StateTime;
import org.pocketbot.protocol.StateTrack;
import org.pocketbot.protocol.StateWheels;
import org.pocketbot.protocol.TrackStatus;

/**
 * A full state packet (97-byte robot_state in a 102-byte frame), at two levels, against Javolution 5.5.1's Struct
 * reading every field of the same payload bytes - as the thesis's library did it (a new Struct per packet,
 * Listing 9.4), and, kinder to Javolution, with one Struct reused for every packet.
 * <ul>
 * <li>payload: the SDK decodes the 97 payload bytes into immutable objects ({@code Frames.decodePayload}) and
 *     encodes them back into a new 97-byte array ({@code encodePayload}); Javolution reads the same 97 bytes
 *     (decode only, as the thesis did; and decode + encode, writing every field into a new 97-byte Struct).</li>
 * <li>frame: the SDK checks the CRC and decodes the 102-byte frame, then encodes a new frame with its CRC;
 *     Javolution gets the same CRC check (the SDK's Crc16) before it reads the payload.</li>
 * </ul>
 * Every benchmark returns its result to JMH, so nothing is dead code.
 */
@State(Scope.Thread)
@BenchmarkMode(Mode.Throughput)
@OutputTimeUnit(TimeUnit.SECONDS)
@Warmup(iterations = 3, time = 1)
@Measurement(iterations = 5, time = 1)
@Fork(value = 1, jvmArgsAppend = {"-XX:+UseParallelGC"})
public class StateCodecBench {
    private byte[] frame;
    private byte[] payload;
    private Packet packet;
    private ByteBuffer payloadBuffer;
    private final JavolutionState reused = new JavolutionState();

    @Setup
    public void setup() {
        RobotState s = new RobotState(
            new StateTime(123456L, 870, 2, 0L), new StateEncoders(-1234, 5678), new StateWheels(180, 175, 520, 515),
            new StateLine(Arrays.asList(100, 220, 900, 1800, 1750, 300, 120, 90), -120, 1),
            new StateLineFollow(LineFollowStatus.FOLLOWING, Colour.BLACK),
            new StateProximity(new ProximitySide(2, 3, IrLed.REAR, DistanceClass.FAR),
                new ProximitySide(0, 0, IrLed.FRONT, DistanceClass.NONE)),
            new StateColour(20, 22, 25, 70, Colour.BLACK), new StateAccel(12, -8, 1003), new StatePower(3870, 140, 312),
            new StateIndicators(1, 100), new StateLocomotion(LocoMode.MOVEMENT, 3, 17, 16),
            new StateTrack(TrackStatus.FOLLOWING, 1, 4, 2), new StateErrors(0, 1, 0, 0, 0, 0, 0, 0, 0));
        frame = Frames.INSTANCE.encode(new StateFull(s), 42);
        payload = Arrays.copyOfRange(frame, Frames.HEADER_SIZE, frame.length - Frames.CRC_SIZE);
        packet = Frames.INSTANCE.decodePayload(StateFull.TYPE, payload, 0, payload.length);
        if (!new StateFull(s).equals(packet) || !Arrays.equals(payload, packet.encodePayload())) {
            throw new IllegalStateException("the payload codec does not round-trip");
        }
        payloadBuffer = ByteBuffer.wrap(payload).order(ByteOrder.LITTLE_ENDIAN);
        JavolutionState j = new JavolutionState();
        if (j.size() != payload.length) throw new IllegalStateException("Javolution struct size " + j.size());
        if (!Arrays.equals(payload, javolutionDecodeEncode())) throw new IllegalStateException("Javolution does not round-trip");
    }

    // ---- payload level

    @Benchmark
    public byte[] sdkPayloadDecodeEncode() {
        return Frames.INSTANCE.decodePayload(StateFull.TYPE, payload, 0, payload.length).encodePayload();
    }

    @Benchmark
    public Packet sdkPayloadDecode() {
        return Frames.INSTANCE.decodePayload(StateFull.TYPE, payload, 0, payload.length);
    }

    @Benchmark
    public byte[] sdkPayloadEncode() {
        return packet.encodePayload();
    }

    @Benchmark
    public long javolutionNewStructPerPacket() {
        JavolutionState s = new JavolutionState();
        s.setByteBuffer(ByteBuffer.wrap(payload).order(ByteOrder.LITTLE_ENDIAN), 0);
        return s.readAll();
    }

    @Benchmark
    public long javolutionReusedStruct() {
        reused.setByteBuffer(payloadBuffer, 0);
        return reused.readAll();
    }

    /** Like for like with sdkPayloadDecodeEncode: a new Struct reads every field, a second one writes them all into new bytes. */
    @Benchmark
    public byte[] javolutionDecodeEncode() {
        JavolutionState in = new JavolutionState();
        in.setByteBuffer(ByteBuffer.wrap(payload).order(ByteOrder.LITTLE_ENDIAN), 0);
        JavolutionState out = new JavolutionState();
        ByteBuffer bytes = ByteBuffer.allocate(payload.length).order(ByteOrder.LITTLE_ENDIAN);
        out.setByteBuffer(bytes, 0);
        out.copyFrom(in);
        return bytes.array();
    }

    // ---- frame level

    @Benchmark
    public byte[] sdkFrameDecodeEncode() {
        Packet p = ((FrameResult.Decoded) Frames.INSTANCE.decode(frame)).getPacket();
        return Frames.INSTANCE.encode(p, 42);
    }

    @Benchmark
    public Packet sdkFrameDecode() {
        return ((FrameResult.Decoded) Frames.INSTANCE.decode(frame)).getPacket();
    }

    @Benchmark
    public byte[] sdkFrameEncode() {
        return Frames.INSTANCE.encode(packet, 42);
    }

    /** Where frame time goes beyond the payload codec: the CRC over header and payload (once per decode, once per encode). */
    @Benchmark
    public int crcOnly() {
        return Crc16.INSTANCE.compute(frame, 0, frame.length - 2);
    }

    /** Javolution with the same frame check as Frames.decode: the CRC (the SDK's Crc16), then a new Struct reads the payload. */
    @Benchmark
    public long javolutionFrameNewStructPerPacket() {
        int n = frame.length - 2;
        int crc = (frame[n] & 0xFF) | ((frame[n + 1] & 0xFF) << 8);
        if (Crc16.INSTANCE.compute(frame, 0, n) != crc) throw new IllegalStateException("bad CRC");
        JavolutionState s = new JavolutionState();
        s.setByteBuffer(ByteBuffer.wrap(frame).order(ByteOrder.LITTLE_ENDIAN), Frames.HEADER_SIZE);
        return s.readAll();
    }

    /** robot_state for Javolution: little-endian, packed (thesis 9.5.2). */
    public static final class JavolutionState extends Struct {
        @Override public ByteOrder byteOrder() { return ByteOrder.LITTLE_ENDIAN; }
        @Override public boolean isPacked() { return true; }

        final Unsigned32 timeMs = new Unsigned32();
        final Unsigned16 tickMaxUs = new Unsigned16();
        final Unsigned16 overruns = new Unsigned16();
        final Unsigned32 lastOverrunMs = new Unsigned32();
        final Signed32 encLeft = new Signed32();
        final Signed32 encRight = new Signed32();
        final Signed16 speedLeft = new Signed16();
        final Signed16 speedRight = new Signed16();
        final Signed16 pwmLeft = new Signed16();
        final Signed16 pwmRight = new Signed16();
        final Unsigned16[] raw = array(new Unsigned16[8]);
        final Signed16 position = new Signed16();
        final Unsigned8 lineFlags = new Unsigned8();
        final Unsigned8 followStatus = new Unsigned8();
        final Unsigned8 followSegment = new Unsigned8();
        final Unsigned8[] proximity = array(new Unsigned8[8]);
        final Unsigned8[] colour = array(new Unsigned8[5]);
        final Signed16 ax = new Signed16();
        final Signed16 ay = new Signed16();
        final Signed16 az = new Signed16();
        final Unsigned16 batteryMv = new Unsigned16();
        final Unsigned16 currentMa = new Unsigned16();
        final Signed16 mcuTemp = new Signed16();
        final Unsigned8 led = new Unsigned8();
        final Unsigned8 irPower = new Unsigned8();
        final Unsigned8 locoMode = new Unsigned8();
        final Unsigned8 queueLength = new Unsigned8();
        final Unsigned16 currentId = new Unsigned16();
        final Unsigned16 finishedId = new Unsigned16();
        final Unsigned8 trackStatus = new Unsigned8();
        final Unsigned8 token = new Unsigned8();
        final Unsigned16 tokenVisits = new Unsigned16();
        final Unsigned8 metId = new Unsigned8();
        final Unsigned16[] errors = array(new Unsigned16[5]);

        void copyFrom(JavolutionState s) {
            timeMs.set(s.timeMs.get()); tickMaxUs.set(s.tickMaxUs.get()); overruns.set(s.overruns.get());
            lastOverrunMs.set(s.lastOverrunMs.get());
            encLeft.set(s.encLeft.get()); encRight.set(s.encRight.get());
            speedLeft.set(s.speedLeft.get()); speedRight.set(s.speedRight.get()); pwmLeft.set(s.pwmLeft.get()); pwmRight.set(s.pwmRight.get());
            for (int i = 0; i < raw.length; i++) raw[i].set(s.raw[i].get());
            position.set(s.position.get()); lineFlags.set(s.lineFlags.get());
            followStatus.set(s.followStatus.get()); followSegment.set(s.followSegment.get());
            for (int i = 0; i < proximity.length; i++) proximity[i].set(s.proximity[i].get());
            for (int i = 0; i < colour.length; i++) colour[i].set(s.colour[i].get());
            ax.set(s.ax.get()); ay.set(s.ay.get()); az.set(s.az.get());
            batteryMv.set(s.batteryMv.get()); currentMa.set(s.currentMa.get()); mcuTemp.set(s.mcuTemp.get());
            led.set(s.led.get()); irPower.set(s.irPower.get()); locoMode.set(s.locoMode.get()); queueLength.set(s.queueLength.get());
            currentId.set(s.currentId.get()); finishedId.set(s.finishedId.get());
            trackStatus.set(s.trackStatus.get()); token.set(s.token.get()); tokenVisits.set(s.tokenVisits.get()); metId.set(s.metId.get());
            for (int i = 0; i < errors.length; i++) errors[i].set(s.errors[i].get());
        }

        long readAll() {
            long sum = timeMs.get() + tickMaxUs.get() + overruns.get() + lastOverrunMs.get() + encLeft.get() + encRight.get()
                + speedLeft.get() + speedRight.get() + pwmLeft.get() + pwmRight.get();
            for (Unsigned16 r : raw) sum += r.get();
            sum += position.get() + lineFlags.get() + followStatus.get() + followSegment.get();
            for (Unsigned8 p : proximity) sum += p.get();
            for (Unsigned8 c : colour) sum += c.get();
            sum += ax.get() + ay.get() + az.get() + batteryMv.get() + currentMa.get() + mcuTemp.get() + led.get()
                + irPower.get() + locoMode.get() + queueLength.get() + currentId.get() + finishedId.get()
            + trackStatus.get() + token.get() + tokenVisits.get() + metId.get();
            for (Unsigned16 e : errors) sum += e.get();
            return sum;
        }
    }
}
