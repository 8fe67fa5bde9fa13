package org.pocketbot.emulator.firmware

import java.lang.ref.Cleaner
import java.lang.ref.Reference
import java.nio.ByteBuffer
import java.nio.ByteOrder
import java.nio.file.Files
import java.nio.file.Path
import java.nio.file.StandardCopyOption

/**
 * The native firmware engine: libpocketbot-firmware.so, the firmware's wasm turned into C by wasm2c and compiled by gcc
 * into a JNI library (firmware/native/engine.c, the other side of these calls: change both together). Each robot gets
 * an instance of its own (own linear memory, globals and table, in the C heap), and a step is one call in that never
 * calls back: the firmware imports nothing (sim_abi.h).
 *
 * Where the library comes from, first found: the file named by `-Dpocketbot.emulator.nativeLibrary=<path>`, else the
 * one the emulator's jar carries for this platform (`native/<os>-<arch>/` beside this class, put there by the Maven
 * build from `make -C firmware native-engine`; only Linux is built). [FirmwareImage.compiled] uses it only when it was
 * built from the very wasm the emulator's Chicory code was, and says which engine runs and why.
 */
internal object NativeEngine {
    const val LIBRARY_PROPERTY = "pocketbot.emulator.nativeLibrary"
    private const val LIBRARY = "libpocketbot-firmware.so"

    /** The library, loaded (once per JVM), or why it is not. */
    sealed interface Status
    class Loaded(
        /** Where it was loaded from, for messages. */
        val from: String,
        /** SHA-256 (hex) of the wasm it was built from. */
        val wasmSha256: String,
    ) : Status
    class Unavailable(val reason: String) : Status

    val status: Status by lazy { load() }

    /** `linux-x86_64` and the like: the folder of the jar's library for this JVM's platform, or null (none is built). */
    fun platform(): String? {
        val os = System.getProperty("os.name").lowercase()
        if (!os.startsWith("linux")) return null
        val arch = when (val a = System.getProperty("os.arch").lowercase()) {
            "amd64", "x86_64" -> "x86_64"
            else -> a
        }
        return "linux-$arch"
    }

    private fun load(): Status {
        val explicit = System.getProperty(LIBRARY_PROPERTY)
        val file: Path
        val from: String
        var temporary = false
        if (explicit != null) {
            file = Path.of(explicit).toAbsolutePath()
            from = file.toString()
            if (!Files.isRegularFile(file)) return Unavailable("-D$LIBRARY_PROPERTY=$explicit is no file")
        } else {
            val platform = platform() ?: return Unavailable(
                "none is built for ${System.getProperty("os.name")} ${System.getProperty("os.arch")} (only for Linux)",
            )
            val url = NativeEngine::class.java.getResource("native/$platform/$LIBRARY")
                ?: return Unavailable("this emulator was built without it for $platform (`make -C firmware native-engine` before Maven)")
            if (url.protocol == "file") {
                file = Path.of(url.toURI())
                from = file.toString()
            } else {
                // In a jar: the dynamic loader needs a file. Removed once loaded (the mapping stays), so none is left over.
                file = Files.createTempFile("pocketbot-firmware-", ".so")
                url.openStream().use { Files.copy(it, file, StandardCopyOption.REPLACE_EXISTING) }
                from = "$LIBRARY for $platform from the emulator's jar"
                temporary = true
            }
        }
        return try {
            System.load(file.toString())
            Loaded(from, wasmSha256())
        } catch (e: UnsatisfiedLinkError) {
            Unavailable("$from does not load: ${e.message}")
        } finally {
            if (temporary) Files.deleteIfExists(file)
        }
    }

    // ---- engine.c (every call that runs firmware turns a trap into an exception) ---------------------------------

    @JvmStatic external fun wasmSha256(): String

    /** A fresh instance; its handle. */
    @JvmStatic external fun instantiate(): Long

    @JvmStatic external fun free(handle: Long)

    /** The instance's linear memory, valid until [free]. */
    @JvmStatic external fun memory(handle: Long): ByteBuffer

    /** What export [ADDRESSES]`[which]` returns (an address, or sim_links). */
    @JvmStatic external fun address(handle: Long, which: Int): Int

    @JvmStatic external fun init(handle: Long, robotId: Int)
    @JvmStatic external fun advance(handle: Long, nowTicks: Long)
    @JvmStatic external fun encoderEdge(handle: Long, wheel: Int, ticks: Long)
    @JvmStatic external fun uartRx(handle: Long, byte: Int)
    @JvmStatic external fun runEvents(handle: Long, count: Int, endTicks: Long)
    @JvmStatic external fun uartTxTake(handle: Long, max: Int): Int
    @JvmStatic external fun linkTxTake(handle: Long, link: Int, max: Int): Int
    @JvmStatic external fun irRx(handle: Long, side: Int, senderId: Int, senderLed: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int)

    /** The exports that take nothing and return an int (the addresses, sim_links), numbered as engine.c's `address`
     *  switch. */
    val ADDRESSES = listOf(
        "sim_events", "sim_inputs", "sim_ir_out", "sim_outputs", "sim_state", "sim_settings", "sim_uart_tx_buffer", "sim_eeprom",
        "sim_links",
    )
}

/**
 * A robot's firmware run by the native engine: an instance of its own in the C heap, whose memory the emulator reads
 * and writes through a direct buffer. Freed by [close] (a power cycle, the emulator closed) or, for an instance nobody
 * closed, once it is unreachable; after [close] every call and memory access throws instead of touching freed memory.
 */
internal class NativeFirmware private constructor(private var handle: Long) : FirmwareInstance(NativeMemory(NativeEngine.memory(handle))) {
    constructor() : this(NativeEngine.instantiate())

    private val freeing: Cleaner.Cleanable = CLEANER.register(this, Free(handle))

    init {
        findAddresses()
    }

    /** The handle, while open. Every call ends with a reachability fence: the cleaner must not free the instance
     *  while a call into it runs. */
    private fun open(): Long = handle.also { check(it != 0L) { "the firmware instance was closed" } }

    override fun address(name: String): Int? {
        val which = NativeEngine.ADDRESSES.indexOf(name)
        if (which < 0) return null
        return NativeEngine.address(open(), which).also { Reference.reachabilityFence(this) }
    }

    override fun init(robotId: Int) {
        NativeEngine.init(open(), robotId)
        Reference.reachabilityFence(this)
    }

    override fun advance(nowTicks: Long) {
        NativeEngine.advance(open(), nowTicks)
        Reference.reachabilityFence(this)
    }

    override fun encoderEdge(wheel: Int, ticks: Long) {
        NativeEngine.encoderEdge(open(), wheel, ticks)
        Reference.reachabilityFence(this)
    }

    override fun uartRx(byte: Int) {
        NativeEngine.uartRx(open(), byte)
        Reference.reachabilityFence(this)
    }

    override fun runEvents(count: Int, endTicks: Long) {
        NativeEngine.runEvents(open(), count, endTicks)
        Reference.reachabilityFence(this)
    }

    override fun uartTxTake(max: Int): Int =
        NativeEngine.uartTxTake(open(), max).also { Reference.reachabilityFence(this) }

    override fun linkTxTake(link: Int, max: Int): Int =
        NativeEngine.linkTxTake(open(), link, max).also { Reference.reachabilityFence(this) }

    override fun irRx(side: Int, senderId: Int, senderLed: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int) {
        NativeEngine.irRx(open(), side, senderId, senderLed, power, len, payloadLo, payloadHi)
        Reference.reachabilityFence(this)
    }

    override fun close() {
        if (handle == 0L) return
        handle = 0L
        (memory as NativeMemory).buffer = CLOSED
        freeing.clean()
    }

    /** Frees an instance; holds the handle only, never the firmware object (which would then never be unreachable). */
    private class Free(private val handle: Long) : Runnable {
        override fun run() = NativeEngine.free(handle)
    }

    private companion object {
        val CLEANER: Cleaner = Cleaner.create()
        val CLOSED: ByteBuffer = ByteBuffer.allocate(0)
    }
}

/** A native instance's linear memory, through a direct buffer over it (little-endian, bounds-checked by the buffer). */
internal class NativeMemory(buffer: ByteBuffer) : FirmwareMemory {
    var buffer: ByteBuffer = buffer.order(ByteOrder.LITTLE_ENDIAN)
        set(value) { field = value.order(ByteOrder.LITTLE_ENDIAN) }

    override val size: Int get() = buffer.capacity()
    override fun read(address: Int): Byte = buffer.get(address)
    override fun readShort(address: Int): Short = buffer.getShort(address)
    override fun readInt(address: Int): Int = buffer.getInt(address)
    override fun readLong(address: Int): Long = buffer.getLong(address)
    override fun writeI32(address: Int, value: Int) { buffer.putInt(address, value) }
    override fun writeLong(address: Int, value: Long) { buffer.putLong(address, value) }
    override fun writeF64(address: Int, value: Double) { buffer.putDouble(address, value) }
    override fun readBytes(address: Int, size: Int): ByteArray = ByteArray(size).also { buffer.get(address, it) }
    override fun write(address: Int, data: ByteArray) { buffer.put(address, data) }
}
