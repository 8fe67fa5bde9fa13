package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.ExportFunction
import com.dylibso.chicory.runtime.GlobalInstance
import com.dylibso.chicory.runtime.ImportValues
import com.dylibso.chicory.runtime.Instance
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
internal class FirmwareEngine(image: FirmwareImage) {
    val memory: LinearMemory
    val instance: Instance
    private var bound: FirmwareInstance? = null
    private val globals: Array<GlobalInstance>

    val init: ExportFunction
    val advance: ExportFunction
    val encoderEdge: ExportFunction
    val uartRx: ExportFunction
    val uartTxTake: ExportFunction
    val irRx: ExportFunction
    val runEvents: ExportFunction

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
    }

    /** The state of a fresh instance (before any call): memory and mutable globals (low and high words). */
    fun initialGlobals(): LongArray = LongArray(globals.size * 2).also { save(it) }

    /** Makes this engine run [fw]'s firmware until [leave]. */
    fun enter(fw: FirmwareInstance) {
        check(bound == null) { "a firmware call from inside another firmware call on the same thread" }
        bound = fw
        memory.bytes = fw.linear.bytes
        val g = fw.globals
        for (k in globals.indices) { globals[k].setValueLow(g[2 * k]); globals[k].setValueHigh(g[2 * k + 1]) }
    }

    fun leave(fw: FirmwareInstance) {
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
