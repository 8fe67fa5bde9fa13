package org.pocketbot.emulator.firmware

/** The sensors of sim_abi.h (`enum sim_sensor`): indices of sim_inputs_t.sensor, each in its unit. */
internal object SimSensor {
    const val BATTERY_MV: Int = 0
    const val CURRENT_MA: Int = 1
    const val MCU_TEMP_DC: Int = 2
    const val ACCEL_X_MG: Int = 3
    const val ACCEL_Y_MG: Int = 4
    const val ACCEL_Z_MG: Int = 5
    const val COLOUR_R: Int = 6
    const val COLOUR_G: Int = 7
    const val COLOUR_B: Int = 8
    const val COLOUR_CLEAR: Int = 9
}

/**
 * A robot's linear memory as the emulator reads and writes it between calls into its firmware: little-endian, every
 * access bounds-checked (an access outside it throws, never touches anything else). Chicory's [LinearMemory] or a
 * buffer over the native engine's memory ([NativeMemory]).
 */
internal interface FirmwareMemory {
    /** Its size in bytes (whole 64 KiB pages). */
    val size: Int
    fun read(address: Int): Byte
    fun readShort(address: Int): Short
    fun readInt(address: Int): Int
    fun readLong(address: Int): Long
    fun writeI32(address: Int, value: Int)
    fun writeLong(address: Int, value: Long)
    fun writeF64(address: Int, value: Double)
    fun readBytes(address: Int, size: Int): ByteArray
    fun write(address: Int, data: ByteArray)
}

/**
 * One robot's firmware: its own linear memory and globals, and typed calls to the exports of
 * firmware/hal/sim/sim_abi.h. How the code runs is the engine's: [ChicoryFirmware] (one Chicory instance per thread
 * that every robot's firmware runs in, in turn) or [NativeFirmware] (an instance of the native engine per robot).
 * Not thread-safe: one thread at a time drives it. [FirmwareImage.instantiate] makes one.
 */
internal sealed class FirmwareInstance(
    /** The instance's linear memory. */
    val memory: FirmwareMemory,
) {
    /** Calls export [name] of sim_abi.h that takes nothing and returns an int (an address in [memory], or sim_links);
     *  null when the firmware lacks it. */
    protected abstract fun address(name: String): Int?

    abstract fun init(robotId: Int)
    abstract fun advance(nowTicks: Long)
    abstract fun encoderEdge(wheel: Int, ticks: Long)
    abstract fun uartRx(byte: Int)

    /**
     * Delivers the first [count] events of the buffer in order, as [advance] and [uartRx] / [encoderEdge] would one by
     * one, then advances to [endTicks] unless it is negative: one call into the instance instead of two per event.
     */
    abstract fun runEvents(count: Int, endTicks: Long)

    /** Takes up to [max] bytes queued for the host; they are at [txBufferAddress]. */
    abstract fun uartTxTake(max: Int): Int

    /** As [uartTxTake], for host link [link] (0: the UART). */
    abstract fun linkTxTake(link: Int, max: Int): Int

    abstract fun irRx(side: Int, senderId: Int, senderLed: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int)

    /** Gives back what the instance holds outside the JVM's heap; any later call or memory access fails. */
    open fun close() {}

    // Addresses in [memory], set by [findAddresses] (fields, not lazy: they are read several times per step).

    /** Addresses of sim_outputs_t, robot_state and settings. */
    var outputsAddress: Int = -1; private set
    var stateAddress: Int = -1; private set
    var settingsAddress: Int = -1; private set
    var txBufferAddress: Int = -1; private set

    /** Address of the event buffer that [runEvents] reads (sim_events). */
    var eventsAddress: Int = -1; private set

    /** Addresses of sim_inputs_t (what the sensors face) and sim_ir_out_t (the IR messages sent). */
    var inputsAddress: Int = -1; private set
    var irOutAddress: Int = -1; private set

    /** Address of the EEPROM (sim_eeprom), or -1 for a firmware without one (the stand-in). */
    var eepromAddress: Int = -1; private set

    /** How many host links the firmware serves at once (sim_links; 1, the UART, for a firmware without it). */
    var linkCount: Int = 1; private set

    /** Asks the firmware where its buffers are and how many host links it serves: the last step of a subclass's
     *  construction. */
    protected fun findAddresses() {
        fun required(name: String): Int = address(name) ?: throw IllegalStateException("the firmware does not export $name")
        eventsAddress = required("sim_events")
        inputsAddress = required("sim_inputs")
        irOutAddress = required("sim_ir_out")
        outputsAddress = required("sim_outputs")
        stateAddress = required("sim_state")
        settingsAddress = required("sim_settings")
        txBufferAddress = required("sim_uart_tx_buffer")
        eepromAddress = address("sim_eeprom") ?: -1
        linkCount = address("sim_links") ?: 1
    }

    /** A copy of the EEPROM, or null when the firmware has none. */
    fun eeprom(): ByteArray? = if (eepromAddress < 0) null else memory.readBytes(eepromAddress, EEPROM_SIZE)

    /** Puts an EEPROM image in place before [init] (a power cycle keeps the EEPROM). */
    fun loadEeprom(bytes: ByteArray) {
        require(bytes.size == EEPROM_SIZE) { "EEPROM image of ${bytes.size} bytes, not $EEPROM_SIZE" }
        if (eepromAddress >= 0) memory.write(eepromAddress, bytes)
    }

    /**
     * Puts event [index] (0 until [EVENT_CAPACITY]) in the buffer for [runEvents]: at [ticks], a byte received
     * ([EVENT_UART_RX], [arg] the byte; [EVENT_LINK_RX] on another link), an encoder edge ([EVENT_ENCODER_EDGE], [arg]
     * the wheel), or a host link opened or closed ([EVENT_LINK_OPEN], [EVENT_LINK_CLOSE], [arg] the link).
     */
    fun putEvent(index: Int, ticks: Long, kind: Int, arg: Int) {
        val at = eventsAddress + index * EVENT_BYTES
        memory.writeLong(at, ticks)
        memory.writeI32(at + 8, kind)
        memory.writeI32(at + 12, arg)
    }

    // sim_inputs_t of sim_abi.h: what the sensors face during the next calls.

    /** The line sensor's conversion: a detector's reading with its emitters off, what a lit emitter adds over white
     *  floor, what it adds more over black tape, and the noise's standard deviation (ADC counts). */
    fun setLineSensorModel(ambientAdc: Double, whiteAdc: Double, spanAdc: Double, noiseAdc: Double) {
        memory.writeF64(inputsAddress + IN_LINE_AMBIENT, ambientAdc)
        memory.writeF64(inputsAddress + IN_LINE_WHITE, whiteAdc)
        memory.writeF64(inputsAddress + IN_LINE_SPAN, spanAdc)
        memory.writeF64(inputsAddress + IN_LINE_NOISE, noiseAdc)
    }

    /** Darkness under line sensor spot [spot] (0..7, left to right), 0 white .. 1 black. */
    fun setLineDark(spot: Int, darkness: Double) { memory.writeF64(inputsAddress + IN_LINE_DARK + 8 * spot, darkness) }

    /** The true value of [SimSensor] [sensor], in its unit. */
    fun setSensor(sensor: Int, value: Double) { memory.writeF64(inputsAddress + IN_SENSOR + 8 * sensor, value) }

    /** Whether readings are noisy, and the state of the noise generator (a splitmix64 stream) they draw from. */
    fun setNoise(on: Boolean, state: Long) {
        memory.writeLong(inputsAddress + IN_NOISE_STATE, state)
        memory.writeI32(inputsAddress + IN_NOISE, if (on) 1 else 0)
    }

    /** The noise generator's state after the firmware drew from it. */
    fun noiseState(): Long = memory.readLong(inputsAddress + IN_NOISE_STATE)

    // sim_ir_out_t of sim_abi.h: the IR messages sent since the last [clearIrOut].

    fun irOutCount(): Int = memory.readInt(irOutAddress).coerceIn(0, IR_OUT_CAPACITY)

    /** Field [field] (IR_SENDER .. IR_PAYLOAD_HI) of message [k]. */
    fun irOut(k: Int, field: Int): Int = memory.readInt(irOutAddress + IR_OUT_MSG + k * IR_MSG_BYTES + 4 * field)

    /** Empties the buffer; returns how many messages found it full since the last call. */
    fun clearIrOut(): Int {
        val dropped = memory.readInt(irOutAddress + IR_OUT_DROPPED)
        memory.writeLong(irOutAddress, 0L) // count and dropped
        return dropped
    }

    // sim_outputs_t of sim_abi.h (the emulator's own contract with the firmware, not part of the protocol).
    fun pwmLeft(): Int = memory.readShort(outputsAddress + OUT_PWM_LEFT).toInt()
    fun pwmRight(): Int = memory.readShort(outputsAddress + OUT_PWM_RIGHT).toInt()
    fun led(): Int = memory.read(outputsAddress + OUT_LED).toInt() and 0xff
    fun lineEmitters(): Int = memory.read(outputsAddress + OUT_LINE_EMITTERS).toInt() and 0xff

    fun readBytes(address: Int, length: Int): ByteArray = memory.readBytes(address, length)

    companion object {
        /** HAL_EEPROM_SIZE of hal.h. */
        const val EEPROM_SIZE: Int = 2048
        /** sim_event_t of sim_abi.h: SIM_EVENT_CAPACITY events of 16 bytes, kinds SIM_EVENT_*. */
        const val EVENT_CAPACITY: Int = 64
        const val EVENT_UART_RX: Int = 0
        const val EVENT_ENCODER_EDGE: Int = 1
        /** A byte on a host link: the argument is `link shl 8 or byte`. */
        const val EVENT_LINK_RX: Int = 2
        /** A host came on link `arg`, or left it. */
        const val EVENT_LINK_OPEN: Int = 3
        const val EVENT_LINK_CLOSE: Int = 4
        private const val EVENT_BYTES = 16
        /** sim_ir_msg_t's fields, in order; SIM_IR_OUT_CAPACITY. */
        const val IR_SENDER: Int = 0
        const val IR_LED: Int = 1
        const val IR_POWER: Int = 2
        const val IR_LEN: Int = 3
        const val IR_PAYLOAD_LO: Int = 4
        const val IR_PAYLOAD_HI: Int = 5
        const val IR_OUT_CAPACITY: Int = 32
        private const val IR_MSG_BYTES = 24
        private const val IR_OUT_DROPPED = 4
        private const val IR_OUT_MSG = 8
        private const val IN_NOISE_STATE = 0
        private const val IN_NOISE = 8
        private const val IN_LINE_AMBIENT = 16
        private const val IN_LINE_WHITE = 24
        private const val IN_LINE_SPAN = 32
        private const val IN_LINE_NOISE = 40
        private const val IN_LINE_DARK = 48
        private const val IN_SENSOR = 112
        private const val OUT_PWM_LEFT = 0
        private const val OUT_PWM_RIGHT = 2
        private const val OUT_LED = 4
        private const val OUT_LINE_EMITTERS = 5
    }
}
