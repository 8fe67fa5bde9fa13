package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.Memory
import com.dylibso.chicory.wasm.types.MemoryLimits

/** What the firmware imports (module "env" of firmware/hal/sim/sim_abi.h), answered by the simulated robot. */
public interface FirmwareHost {
    /**
     * One line sensor ADC sweep: the four detectors (0..3) read now with the emitters in the bit mask lit,
     * each 0..4095, detector d in bits 16d..16d+15 (sim_abi.h line_adc_sweep).
     */
    public fun lineAdcSweep(emitters: Int): Long

    /** One of the [SimSensor] values, in its physical unit. */
    public fun sensorRead(sensor: Int): Int

    /** The firmware sends an IR message now. */
    public fun irSend(senderId: Int, led: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int)
}

/** sensor_read ids of sim_abi.h. */
public object SimSensor {
    public const val BATTERY_MV: Int = 0
    public const val CURRENT_MA: Int = 1
    public const val MCU_TEMP_DC: Int = 2
    public const val ACCEL_X_MG: Int = 3
    public const val ACCEL_Y_MG: Int = 4
    public const val ACCEL_Z_MG: Int = 5
    public const val COLOUR_R: Int = 6
    public const val COLOUR_G: Int = 7
    public const val COLOUR_B: Int = 8
    public const val COLOUR_CLEAR: Int = 9
}

/**
 * One robot's firmware: its own linear memory and globals, and typed calls to the exports of
 * firmware/hal/sim/sim_abi.h, which run in the calling thread's [FirmwareEngine] (one Chicory instance per thread
 * that every robot's firmware runs in, in turn). Not thread-safe: one thread at a time drives it.
 */
public class FirmwareInstance(private val image: FirmwareImage, internal val host: FirmwareHost) {
    /** An engine of its own when the image's robots cannot share one. */
    private val ownEngine: FirmwareEngine? = if (image.sharesEngines) null else FirmwareEngine(image)

    internal val linear = LinearMemory(MemoryLimits(image.initialMemory.size / Memory.PAGE_SIZE)).apply {
        bytes = image.initialMemory.copyOf()
    }

    /** The mutable globals between calls, low and high word each (see [FirmwareEngine.enter]). */
    internal val globals: LongArray = image.initialGlobals.copyOf()

    /** The instance's linear memory (little-endian). */
    public val memory: Memory get() = linear

    /** Addresses of sim_outputs_t, robot_state and settings in [memory]. */
    public val outputsAddress: Int
    public val stateAddress: Int
    public val settingsAddress: Int
    public val txBufferAddress: Int

    /** Address of the event buffer that [runEvents] reads (sim_events). */
    public val eventsAddress: Int

    /** Address of the EEPROM (sim_eeprom), or -1 for a firmware without one (the stand-in). */
    public val eepromAddress: Int

    init {
        fun address(name: String): Int = call { it.instance.export(name).apply()[0].toInt() }
        eventsAddress = address("sim_events")
        outputsAddress = address("sim_outputs")
        stateAddress = address("sim_state")
        settingsAddress = address("sim_settings")
        txBufferAddress = address("sim_uart_tx_buffer")
        eepromAddress = call { it.exportOrNull("sim_eeprom")?.apply()?.get(0)?.toInt() } ?: -1
    }

    /** Runs [block] in an engine bound to this firmware. */
    private inline fun <T> call(block: (FirmwareEngine) -> T): T {
        val engine = ownEngine ?: image.engine()
        engine.enter(this)
        try {
            return block(engine)
        } catch (t: Throwable) {
            if (ownEngine == null) image.discardEngine()
            throw t
        } finally {
            engine.leave(this)
        }
    }

    /** A copy of the EEPROM, or null when the firmware has none. */
    public fun eeprom(): ByteArray? = if (eepromAddress < 0) null else memory.readBytes(eepromAddress, EEPROM_SIZE)

    /** Puts an EEPROM image in place before [init] (a power cycle keeps the EEPROM). */
    public fun loadEeprom(bytes: ByteArray) {
        require(bytes.size == EEPROM_SIZE) { "EEPROM image of ${bytes.size} bytes, not $EEPROM_SIZE" }
        if (eepromAddress >= 0) memory.write(eepromAddress, bytes)
    }

    public fun init(robotId: Int) { call { it.init.apply(robotId.toLong()) } }

    public fun advance(nowTicks: Long) { call { it.advance.apply(nowTicks) } }

    public fun encoderEdge(wheel: Int, ticks: Long) { call { it.encoderEdge.apply(wheel.toLong(), ticks) } }

    public fun uartRx(byte: Int) { call { it.uartRx.apply(byte.toLong()) } }

    /**
     * Puts event [index] (0 until [EVENT_CAPACITY]) in the buffer for [runEvents]: at [ticks], a byte received
     * ([EVENT_UART_RX], [arg] the byte) or an encoder edge ([EVENT_ENCODER_EDGE], [arg] the wheel).
     */
    public fun putEvent(index: Int, ticks: Long, kind: Int, arg: Int) {
        val at = eventsAddress + index * EVENT_BYTES
        linear.writeLong(at, ticks)
        linear.writeI32(at + 8, kind)
        linear.writeI32(at + 12, arg)
    }

    /**
     * Delivers the first [count] events of the buffer in order, as [advance] and [uartRx] / [encoderEdge] would one by
     * one, then advances to [endTicks] unless it is negative: one call into the instance instead of two per event.
     */
    public fun runEvents(count: Int, endTicks: Long) { call { it.runEvents.apply(count.toLong(), endTicks) } }

    /** Takes up to [max] bytes queued for the host; they are at [txBufferAddress]. */
    public fun uartTxTake(max: Int): Int = call { it.uartTxTake.apply(max.toLong())[0].toInt() }

    public fun irRx(side: Int, senderId: Int, senderLed: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int) {
        call { it.irRx.apply(side.toLong(), senderId.toLong(), senderLed.toLong(), power.toLong(), len.toLong(), payloadLo.toLong(), payloadHi.toLong()) }
    }

    // sim_outputs_t of sim_abi.h (the emulator's own contract with the firmware, not part of the protocol).
    public fun pwmLeft(): Int = linear.readShort(outputsAddress + OUT_PWM_LEFT).toInt()
    public fun pwmRight(): Int = linear.readShort(outputsAddress + OUT_PWM_RIGHT).toInt()
    public fun led(): Int = linear.read(outputsAddress + OUT_LED).toInt() and 0xff
    public fun lineEmitters(): Int = linear.read(outputsAddress + OUT_LINE_EMITTERS).toInt() and 0xff

    public fun readBytes(address: Int, length: Int): ByteArray = linear.readBytes(address, length)

    public companion object {
        /** HAL_EEPROM_SIZE of hal.h. */
        public const val EEPROM_SIZE: Int = 2048
        /** sim_event_t of sim_abi.h: SIM_EVENT_CAPACITY events of 16 bytes, kinds SIM_EVENT_*. */
        public const val EVENT_CAPACITY: Int = 64
        public const val EVENT_UART_RX: Int = 0
        public const val EVENT_ENCODER_EDGE: Int = 1
        private const val EVENT_BYTES = 16
        private const val OUT_PWM_LEFT = 0
        private const val OUT_PWM_RIGHT = 2
        private const val OUT_LED = 4
        private const val OUT_LINE_EMITTERS = 5
    }
}
