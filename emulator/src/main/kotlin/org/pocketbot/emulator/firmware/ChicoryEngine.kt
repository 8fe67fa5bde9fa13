package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.ExportFunction
import com.dylibso.chicory.runtime.GlobalInstance
import com.dylibso.chicory.runtime.ImportValues
import com.dylibso.chicory.runtime.Instance
import com.dylibso.chicory.runtime.Memory
import com.dylibso.chicory.wasm.types.MemoryLimits
import com.dylibso.chicory.wasm.types.MutabilityType

/**
 * One Chicory instance of a firmware image that runs the firmware of many robots, one call at a time, on one thread.
 *
 * Between calls into it, a firmware's whole state is its linear memory and its mutable globals (for a C firmware,
 * the stack pointer): [enter] points the instance's memory at a robot's own bytes and loads that robot's globals,
 * [leave] stores them back. Robots then share everything else (the instance, its tables and function objects,
 * the JIT's code), so stepping a robot touches its own memory and little more: with a thousand robots what a step
 * costs is mostly the cache lines it touches. [FirmwareImage] keeps one engine per thread, or one per robot for a
 * module whose code changes its tables or data segments (state the engine does not swap).
 */
internal class ChicoryEngine(image: FirmwareImage) {
    val memory: LinearMemory
    val instance: Instance
    private var bound: ChicoryFirmware? = null
    private val globals: Array<GlobalInstance>

    val init: ExportFunction
    val advance: ExportFunction
    val encoderEdge: ExportFunction
    val uartRx: ExportFunction
    val uartTxTake: ExportFunction
    val irRx: ExportFunction
    val runEvents: ExportFunction
    /** Null in a firmware that serves one host link only (the UART). */
    val linkTxTake: ExportFunction?

    init {
        // The firmware imports nothing (sim_abi.h): sensor readings and IR messages are data in its memory.
        var created: LinearMemory? = null
        val builder = Instance.builder(image.module).withImportValues(ImportValues.empty())
            .withMemoryFactory { limits -> LinearMemory(limits).also { created = it } }
        image.machineFactory?.let { builder.withMachineFactory(it) }
        instance = builder.build()
        memory = checkNotNull(created) { "the firmware has no linear memory" }
        val imported = image.module.importSection().count(com.dylibso.chicory.wasm.types.ExternalType.GLOBAL)
        globals = (0 until image.module.globalSection().globalCount())
            .filter { image.module.globalSection().getGlobal(it).mutabilityType() == MutabilityType.Var }
            .map { instance.global(imported + it) }
            .toTypedArray()
        init = instance.export("sim_init")
        advance = instance.export("sim_advance")
        encoderEdge = instance.export("sim_encoder_edge")
        uartRx = instance.export("sim_uart_rx")
        uartTxTake = instance.export("sim_uart_tx_take")
        irRx = instance.export("sim_ir_rx")
        runEvents = instance.export("sim_run_events")
        linkTxTake = exportOrNull("sim_link_tx_take")
    }

    /** The state of a fresh instance (before any call): memory and mutable globals (low and high words). */
    fun initialGlobals(): LongArray = LongArray(globals.size * 2).also { save(it) }

    /** Makes this engine run [fw]'s firmware until [leave]. */
    fun enter(fw: ChicoryFirmware) {
        check(bound == null) { "a firmware call from inside another firmware call on the same thread" }
        bound = fw
        memory.bytes = fw.linear.bytes
        val g = fw.globals
        for (k in globals.indices) { globals[k].setValueLow(g[2 * k]); globals[k].setValueHigh(g[2 * k + 1]) }
    }

    fun leave(fw: ChicoryFirmware) {
        fw.linear.bytes = memory.bytes // a memory.grow replaced the array
        save(fw.globals)
        memory.bytes = EMPTY
        bound = null
    }

    private fun save(into: LongArray) {
        for (k in globals.indices) { into[2 * k] = globals[k].valueLow; into[2 * k + 1] = globals[k].valueHigh }
    }

    /** Export [name] of this instance, or null. */
    fun exportOrNull(name: String): ExportFunction? = runCatching { instance.export(name) }.getOrNull()

    private companion object {
        val EMPTY = ByteArray(0)
    }
}

/**
 * A robot's firmware run by Chicory: its linear memory and mutable globals live here between calls, and each call runs
 * in the calling thread's [ChicoryEngine] (see there), or in an engine of its own for an image whose robots cannot
 * share one.
 */
internal class ChicoryFirmware(private val image: FirmwareImage) : FirmwareInstance(
    LinearMemory(MemoryLimits(image.initialMemory.size / Memory.PAGE_SIZE)).apply { bytes = image.initialMemory.copyOf() },
) {
    private val ownEngine: ChicoryEngine? = if (image.sharesEngines) null else ChicoryEngine(image)

    internal val linear: LinearMemory get() = memory as LinearMemory

    /** The mutable globals between calls, low and high word each (see [ChicoryEngine.enter]). */
    internal val globals: LongArray = image.initialGlobals.copyOf()

    init {
        findAddresses()
    }

    /** Runs [block] in an engine bound to this firmware. */
    private inline fun <T> call(block: (ChicoryEngine) -> T): T {
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

    override fun address(name: String): Int? = call { it.exportOrNull(name)?.apply()?.get(0)?.toInt() }

    override fun init(robotId: Int) { call { it.init.apply(robotId.toLong()) } }

    override fun advance(nowTicks: Long) { call { it.advance.apply(nowTicks) } }

    override fun encoderEdge(wheel: Int, ticks: Long) { call { it.encoderEdge.apply(wheel.toLong(), ticks) } }

    override fun uartRx(byte: Int) { call { it.uartRx.apply(byte.toLong()) } }

    override fun runEvents(count: Int, endTicks: Long) { call { it.runEvents.apply(count.toLong(), endTicks) } }

    override fun uartTxTake(max: Int): Int = call { it.uartTxTake.apply(max.toLong())[0].toInt() }

    override fun linkTxTake(link: Int, max: Int): Int =
        if (link == 0) uartTxTake(max) else call { it.linkTxTake?.apply(link.toLong(), max.toLong())?.get(0)?.toInt() ?: 0 }

    override fun irRx(side: Int, senderId: Int, senderLed: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int) {
        call { it.irRx.apply(side.toLong(), senderId.toLong(), senderLed.toLong(), power.toLong(), len.toLong(), payloadLo.toLong(), payloadHi.toLong()) }
    }
}
