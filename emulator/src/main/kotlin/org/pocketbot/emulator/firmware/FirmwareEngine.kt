package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.ExportFunction
import com.dylibso.chicory.runtime.GlobalInstance
import com.dylibso.chicory.runtime.HostFunction
import com.dylibso.chicory.runtime.ImportValues
import com.dylibso.chicory.runtime.Instance
import com.dylibso.chicory.runtime.WasmFunctionHandle
import com.dylibso.chicory.wasm.types.FunctionType
import com.dylibso.chicory.wasm.types.MutabilityType
import com.dylibso.chicory.wasm.types.ValType

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
    private var host: FirmwareHost? = null
    private var bound: FirmwareInstance? = null
    // One result array per engine, reused: Chicory reads it before the next host call, and these calls happen
    // several times per robot and simulated millisecond.
    private val sweepResult = LongArray(1)
    private val sensorResult = LongArray(1)
    private val globals: Array<GlobalInstance>

    val init: ExportFunction
    val advance: ExportFunction
    val encoderEdge: ExportFunction
    val uartRx: ExportFunction
    val uartTxTake: ExportFunction
    val irRx: ExportFunction
    val runEvents: ExportFunction

    init {
        val i32 = ValType.I32
        val i64 = ValType.I64
        val imports = ImportValues.builder()
            .addFunction(
                HostFunction("env", "line_adc_sweep", FunctionType.of(listOf(i32), listOf(i64)), HostCall(LINE_ADC_SWEEP)),
                HostFunction("env", "sensor_read", FunctionType.of(listOf(i32), listOf(i32)), HostCall(SENSOR_READ)),
                HostFunction("env", "ir_send", FunctionType.of(listOf(i32, i32, i32, i32, i32, i32), listOf()), HostCall(IR_SEND)),
            )
            .build()
        var created: LinearMemory? = null
        val builder = Instance.builder(image.module).withImportValues(imports)
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
        host = fw.host
        memory.bytes = fw.linear.bytes
        val g = fw.globals
        for (k in globals.indices) { globals[k].setValueLow(g[2 * k]); globals[k].setValueHigh(g[2 * k + 1]) }
    }

    fun leave(fw: FirmwareInstance) {
        fw.linear.bytes = memory.bytes // a memory.grow replaced the array
        save(fw.globals)
        memory.bytes = EMPTY
        host = null
        bound = null
    }

    private fun save(into: LongArray) {
        for (k in globals.indices) { into[2 * k] = globals[k].valueLow; into[2 * k + 1] = globals[k].valueHigh }
    }

    /**
     * The firmware's imports, all of one class: the compiled firmware calls every import through one call site, which
     * then sees a single receiver class and the JIT inlines the call (three lambdas made it a virtual call).
     */
    private inner class HostCall(private val import: Int) : WasmFunctionHandle {
        override fun apply(instance: Instance, args: LongArray): LongArray? {
            val host = host!!
            return when (import) {
                LINE_ADC_SWEEP -> sweepResult.also { it[0] = host.lineAdcSweep(args[0].toInt()) }
                SENSOR_READ -> sensorResult.also { it[0] = host.sensorRead(args[0].toInt()).toLong() }
                else -> {
                    host.irSend(args[0].toInt(), args[1].toInt(), args[2].toInt(), args[3].toInt(), args[4].toInt(), args[5].toInt())
                    null
                }
            }
        }
    }

    /** Export [name] of this instance, or null. */
    fun exportOrNull(name: String): ExportFunction? = runCatching { instance.export(name) }.getOrNull()

    private companion object {
        val EMPTY = ByteArray(0)
        const val LINE_ADC_SWEEP = 0
        const val SENSOR_READ = 1
        const val IR_SEND = 2
    }
}
