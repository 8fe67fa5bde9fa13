package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.ByteArrayMemory
import com.dylibso.chicory.runtime.ExportFunction
import com.dylibso.chicory.runtime.HostFunction
import com.dylibso.chicory.runtime.ImportValues
import com.dylibso.chicory.runtime.Instance
import com.dylibso.chicory.runtime.Memory
import com.dylibso.chicory.wasm.types.FunctionType
import com.dylibso.chicory.wasm.types.ValType

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
 * One robot's firmware: a Chicory instance with its own linear memory, and typed calls to the exports of
 * firmware/hal/sim/sim_abi.h. Not thread-safe: one thread at a time drives it.
 */
public class FirmwareInstance(image: FirmwareImage, host: FirmwareHost) {
    private val fastMemory = System.getProperty("pocketbot.emulator.memory", "array") == "array"
    private val sweepResult = LongArray(1)
    private val sensorResult = LongArray(1)

    private val instance: Instance
    private val init: ExportFunction
    private val advance: ExportFunction
    private val encoderEdge: ExportFunction
    private val uartRx: ExportFunction
    private val uartTxTake: ExportFunction
    private val irRx: ExportFunction
    private val runEvents: ExportFunction

    /** The instance's linear memory (little-endian). */
    public val memory: Memory

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
        val i32 = ValType.I32
        val i64 = ValType.I64
        val imports = ImportValues.builder()
            .addFunction(
                // One result array per instance, reused: Chicory reads it before the next host call, and these
                // calls happen several times per robot and simulated millisecond.
                HostFunction("env", "line_adc_sweep", FunctionType.of(listOf(i32), listOf(i64))) { _, args ->
                    sweepResult[0] = host.lineAdcSweep(args[0].toInt())
                    sweepResult
                },
                HostFunction("env", "sensor_read", FunctionType.of(listOf(i32), listOf(i32))) { _, args ->
                    sensorResult[0] = host.sensorRead(args[0].toInt()).toLong()
                    sensorResult
                },
                HostFunction("env", "ir_send", FunctionType.of(listOf(i32, i32, i32, i32, i32, i32), listOf())) { _, args ->
                    host.irSend(args[0].toInt(), args[1].toInt(), args[2].toInt(), args[3].toInt(), args[4].toInt(), args[5].toInt())
                    null
                },
            )
            .build()
        val builder = Instance.builder(image.module).withImportValues(imports)
            .withMemoryFactory { limits -> if (fastMemory) ByteArrayMemory(limits) else com.dylibso.chicory.runtime.ByteBufferMemory(limits) }
        image.machineFactory?.let { builder.withMachineFactory(it) }
        instance = builder.build()
        memory = instance.memory()
        init = instance.export("sim_init")
        advance = instance.export("sim_advance")
        encoderEdge = instance.export("sim_encoder_edge")
        uartRx = instance.export("sim_uart_rx")
        uartTxTake = instance.export("sim_uart_tx_take")
        irRx = instance.export("sim_ir_rx")
        runEvents = instance.export("sim_run_events")
        eventsAddress = instance.export("sim_events").apply()[0].toInt()
        outputsAddress = instance.export("sim_outputs").apply()[0].toInt()
        stateAddress = instance.export("sim_state").apply()[0].toInt()
        settingsAddress = instance.export("sim_settings").apply()[0].toInt()
        txBufferAddress = instance.export("sim_uart_tx_buffer").apply()[0].toInt()
        eepromAddress = runCatching { instance.export("sim_eeprom") }.getOrNull()?.apply()?.get(0)?.toInt() ?: -1
    }

    /** A copy of the EEPROM, or null when the firmware has none. */
    public fun eeprom(): ByteArray? = if (eepromAddress < 0) null else memory.readBytes(eepromAddress, EEPROM_SIZE)

    /** Puts an EEPROM image in place before [init] (a power cycle keeps the EEPROM). */
    public fun loadEeprom(bytes: ByteArray) {
        require(bytes.size == EEPROM_SIZE) { "EEPROM image of ${bytes.size} bytes, not $EEPROM_SIZE" }
        if (eepromAddress >= 0) memory.write(eepromAddress, bytes)
    }

    public fun init(robotId: Int) { init.apply(robotId.toLong()) }

    public fun advance(nowTicks: Long) { advance.apply(nowTicks) }

    public fun encoderEdge(wheel: Int, ticks: Long) { encoderEdge.apply(wheel.toLong(), ticks) }

    public fun uartRx(byte: Int) { uartRx.apply(byte.toLong()) }

    /**
     * Puts event [index] (0 until [EVENT_CAPACITY]) in the buffer for [runEvents]: at [ticks], a byte received
     * ([EVENT_UART_RX], [arg] the byte) or an encoder edge ([EVENT_ENCODER_EDGE], [arg] the wheel).
     */
    public fun putEvent(index: Int, ticks: Long, kind: Int, arg: Int) {
        val at = eventsAddress + index * EVENT_BYTES
        memory.writeLong(at, ticks)
        memory.writeI32(at + 8, kind)
        memory.writeI32(at + 12, arg)
    }

    /**
     * Delivers the first [count] events of the buffer in order, as [advance] and [uartRx] / [encoderEdge] would one by
     * one, then advances to [endTicks] unless it is negative: one call into the instance instead of two per event.
     */
    public fun runEvents(count: Int, endTicks: Long) { runEvents.apply(count.toLong(), endTicks) }

    /** Takes up to [max] bytes queued for the host; they are at [txBufferAddress]. */
    public fun uartTxTake(max: Int): Int = uartTxTake.apply(max.toLong())[0].toInt()

    public fun irRx(side: Int, senderId: Int, senderLed: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int) {
        irRx.apply(side.toLong(), senderId.toLong(), senderLed.toLong(), power.toLong(), len.toLong(), payloadLo.toLong(), payloadHi.toLong())
    }

    // sim_outputs_t of sim_abi.h (the emulator's own contract with the firmware, not part of the protocol).
    public fun pwmLeft(): Int = memory.readShort(outputsAddress + OUT_PWM_LEFT).toInt()
    public fun pwmRight(): Int = memory.readShort(outputsAddress + OUT_PWM_RIGHT).toInt()
    public fun led(): Int = memory.read(outputsAddress + OUT_LED).toInt() and 0xff
    public fun lineEmitters(): Int = memory.read(outputsAddress + OUT_LINE_EMITTERS).toInt() and 0xff

    public fun readBytes(address: Int, length: Int): ByteArray = memory.readBytes(address, length)

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
