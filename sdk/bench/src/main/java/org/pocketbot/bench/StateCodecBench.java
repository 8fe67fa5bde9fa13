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
import org.pocketbot.protocol.FrameResult;
import org.pocketbot.protocol.Frames;
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
import org.pocketbot.protocol.StateWheels;

/**
 * A full state packet (88-byte robot_state in a 93-byte frame): the SDK's decode (CRC check, all fields into
 * immutable objects) plus encode (back to a frame with CRC), against Javolution 5.5.1's Struct reading every
 * field of the same bytes - as the thesis's library did it (a new Struct per packet, Listing 9.4), and, kinder to
 * Javolution, with one Struct reused for every packet.
 */
@State(Scope.Thread)
@BenchmarkMode(Mode.Throughput)
@OutputTimeUnit(TimeUnit.SECONDS)
@Warmup(iterations = 3, time = 1)
@Measurement(iterations = 5, time = 1)
@Fork(value = 1, jvmArgsAppend = {"-XX:+UseParallelGC"})
public class StateCodecBench {
    private byte[] frame;
    private ByteBuffer buffer;
    private final JavolutionState reused = new JavolutionState();

    @Setup
    public void setup() {
        RobotState s = new RobotState(
            new StateTime(123456L, 870, 2), new StateEncoders(-1234, 5678), new StateWheels(180, 175, 520, 515),
            new StateLine(Arrays.asList(100, 220, 900, 1800, 1750, 300, 120, 90), -120, 1), new StateLineFollow(1, 2),
            new StateProximity(new ProximitySide(2, 3, 2, 1), new ProximitySide(0, 0, 0, 0)),
            new StateColour(20, 22, 25, 70, 2), new StateAccel(12, -8, 1003), new StatePower(3870, 140, 312),
            new StateIndicators(1, 100), new StateLocomotion(1, 3, 17, 16), new StateErrors(0, 1, 0, 0, 0));
        frame = Frames.INSTANCE.encode(new StateFull(s), 42);
        buffer = ByteBuffer.wrap(frame).order(ByteOrder.LITTLE_ENDIAN);
    }

    @Benchmark
    public byte[] sdkDecodeEncode() {
        FrameResult r = Frames.INSTANCE.decode(frame);
        Packet p = ((FrameResult.Decoded) r).getPacket();
        return Frames.INSTANCE.encode(p, 42);
    }

    @Benchmark
    public Packet sdkDecode() {
        return ((FrameResult.Decoded) Frames.INSTANCE.decode(frame)).getPacket();
    }

    /** Where the time goes: the CRC over header and payload, computed once by decode and once by encode. */
    @Benchmark
    public int crcOnly() {
        return org.pocketbot.protocol.Crc16.INSTANCE.compute(frame, 0, frame.length - 2);
    }

    @Benchmark
    public long javolutionNewStructPerPacket() {
        JavolutionState s = new JavolutionState();
        s.setByteBuffer(ByteBuffer.wrap(frame).order(ByteOrder.LITTLE_ENDIAN), 3);
        return s.readAll();
    }

    @Benchmark
    public long javolutionReusedStruct() {
        reused.setByteBuffer(buffer, 3);
        return reused.readAll();
    }

    /** robot_state for Javolution: little-endian, packed (thesis 9.5.2). */
    public static final class JavolutionState extends Struct {
        @Override public ByteOrder byteOrder() { return ByteOrder.LITTLE_ENDIAN; }
        @Override public boolean isPacked() { return true; }

        final Unsigned32 timeMs = new Unsigned32();
        final Unsigned16 tickMaxUs = new Unsigned16();
        final Unsigned16 overruns = new Unsigned16();
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
        final Unsigned16[] errors = array(new Unsigned16[5]);

        long readAll() {
            long sum = timeMs.get() + tickMaxUs.get() + overruns.get() + encLeft.get() + encRight.get()
                + speedLeft.get() + speedRight.get() + pwmLeft.get() + pwmRight.get();
            for (Unsigned16 r : raw) sum += r.get();
            sum += position.get() + lineFlags.get() + followStatus.get() + followSegment.get();
            for (Unsigned8 p : proximity) sum += p.get();
            for (Unsigned8 c : colour) sum += c.get();
            sum += ax.get() + ay.get() + az.get() + batteryMv.get() + currentMa.get() + mcuTemp.get() + led.get()
                + irPower.get() + locoMode.get() + queueLength.get() + currentId.get() + finishedId.get();
            for (Unsigned16 e : errors) sum += e.get();
            return sum;
        }
    }
}
