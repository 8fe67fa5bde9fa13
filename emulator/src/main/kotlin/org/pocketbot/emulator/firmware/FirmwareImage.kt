package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.Instance
import com.dylibso.chicory.runtime.Machine
import com.dylibso.chicory.wasm.Parser
import com.dylibso.chicory.wasm.WasmModule
import com.dylibso.chicory.wasm.types.OpCode
import com.sun.management.HotSpotDiagnosticMXBean
import java.lang.management.ManagementFactory
import java.nio.file.Files
import java.nio.file.Path
import java.util.function.Function

/**
 * A firmware build ready to instantiate: the parsed WebAssembly module and how to run it.
 * Every robot gets its own [FirmwareInstance] (own linear memory, own globals) from one image; the code runs in one
 * [FirmwareEngine] per thread.
 */
public class FirmwareImage internal constructor(
    internal val module: WasmModule,
    internal val machineFactory: Function<Instance, Machine>?,
    /** Where it came from, for messages. */
    public val origin: String,
) {
    /**
     * Whether robots may share an engine: true unless the code changes tables or data segments, state an engine
     * does not swap between robots. The compiled image carries no code to look at; it is the firmware, built by clang
     * from C, which never does (FirmwareEngineTest checks its wasm).
     */
    internal val sharesEngines: Boolean = !changesTablesOrSegments(module)

    private val engines = ThreadLocal.withInitial { FirmwareEngine(this) }

    /** This thread's engine (for an image whose robots may share one). */
    internal fun engine(): FirmwareEngine = engines.get()

    /** After a call failed: the engine may be in the middle of something, the thread's next call builds a new one. */
    internal fun discardEngine() = engines.remove()

    /** A fresh instance's memory and mutable globals, copied into every new robot. */
    internal val initialMemory: ByteArray
    internal val initialGlobals: LongArray

    init {
        val fresh = FirmwareEngine(this)
        initialMemory = fresh.memory.bytes.copyOf()
        initialGlobals = fresh.initialGlobals()
        if (sharesEngines) engines.set(fresh) // this thread's engine: [FirmwareEngine.enter] loads a robot's state into it

    }

    public companion object {
        private const val COMPILED_CLASS = "org.pocketbot.emulator.firmware.FirmwareModule"
        private const val COMPILED_HCI_CLASS = "org.pocketbot.emulator.firmware.HciFirmwareModule"

        /**
         * The firmware compiled to JVM bytecode at build time (chicory-compiler-maven-plugin, from
         * firmware/build/wasm/pocketbot.wasm). Throws [IllegalStateException] when the emulator was built
         * without the firmware (run `make -C firmware wasm`, then rebuild the emulator).
         *
         * Logs a warning (once, through `System.Logger` "org.pocketbot.emulator") when the JVM was started without
         * `-XX:-DontCompileHugeMethods`: HotSpot then never compiles the firmware's largest functions, and the
         * emulator runs at about half its speed (emulator/README.md, "Performance").
         */
        public fun compiled(): FirmwareImage = compiled(COMPILED_CLASS, "pocketbot.wasm")

        /**
         * The HCI build of the firmware (firmware/build/wasm/pocketbot-hci.wasm, compiled at build time like
         * [compiled]): its UART carries H4 to a Bluetooth controller and hosts reach it over Bluetooth
         * (see [org.pocketbot.emulator.RobotHandle.attachH4]). Throws [IllegalStateException] when the emulator was
         * built without it.
         */
        public fun compiledHci(): FirmwareImage = compiled(COMPILED_HCI_CLASS, "pocketbot-hci.wasm")

        private fun compiled(className: String, wasm: String): FirmwareImage {
            hugeMethodsChecked
            val cls = try {
                Class.forName(className)
            } catch (e: ClassNotFoundException) {
                throw IllegalStateException(
                    "the emulator was built without firmware/build/wasm/$wasm: run `make -C firmware wasm`, then rebuild the emulator", e,
                )
            }
            val module = cls.getMethod("load").invoke(null) as WasmModule
            val create = cls.getMethod("create", Instance::class.java)
            return FirmwareImage(module, Function { instance -> create.invoke(null, instance) as Machine }, "compiled:$className")
        }

        /** Warns once per JVM if huge methods stay interpreted (see [compiled]). */
        private val hugeMethodsChecked: Unit by lazy {
            if (hugeMethodsStayInterpreted()) System.getLogger("org.pocketbot.emulator").log(
                System.Logger.Level.WARNING,
                "the JVM runs without -XX:-DontCompileHugeMethods: HotSpot leaves the firmware's largest functions " +
                    "interpreted and the emulator runs at about half its speed; add the flag to the java command line",
            )
        }

        /** True when HotSpot says it will not compile methods over 8000 bytecode bytes; false on other JVMs. */
        internal fun hugeMethodsStayInterpreted(): Boolean = runCatching {
            ManagementFactory.getPlatformMXBean(HotSpotDiagnosticMXBean::class.java)
                .getVMOption("DontCompileHugeMethods").value == "true"
        }.getOrDefault(false)

        /** True when the build-time compiled firmware is on the class path. */
        public fun compiledAvailable(): Boolean =
            runCatching { Class.forName(COMPILED_CLASS) }.isSuccess

        /** A .wasm file run by Chicory's interpreter (about 20x slower than [compiled]): for other builds and tests. */
        public fun interpreted(wasm: ByteArray, origin: String = "wasm bytes"): FirmwareImage =
            FirmwareImage(Parser.parse(wasm), null, origin)

        public fun interpreted(path: Path): FirmwareImage = interpreted(Files.readAllBytes(path), path.toString())

        private val STATE_CHANGING_OPS = setOf(
            OpCode.TABLE_SET, OpCode.TABLE_GROW, OpCode.TABLE_FILL, OpCode.TABLE_COPY, OpCode.TABLE_INIT,
            OpCode.ELEM_DROP, OpCode.DATA_DROP,
        )

        internal fun changesTablesOrSegments(module: WasmModule): Boolean =
            module.codeSection().functionBodies().any { body -> body.instructions().any { it.opcode() in STATE_CHANGING_OPS } }
    }
}
