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
import java.security.MessageDigest
import java.util.function.Function

/** What runs a firmware's code. Both give the same results, bit for bit; they differ in speed and in where they run. */
public enum class FirmwareEngine {
    /**
     * The firmware's wasm compiled to machine code (wasm2c and gcc) in a JNI library the emulator's jar carries for
     * Linux; each robot an instance of its own. About twice as fast as [CHICORY] (emulator/README.md, Performance).
     */
    NATIVE,

    /** The firmware's wasm run by Chicory (compiled to JVM bytecode at build time, or interpreted): runs on any JVM. */
    CHICORY,
}

/**
 * A firmware build ready to instantiate: the parsed WebAssembly module and how to run it ([engine]).
 * Every robot gets its own instance (own linear memory, own globals) from one image; under Chicory the code runs in
 * one [ChicoryEngine] per thread.
 */
public class FirmwareImage internal constructor(
    internal val module: WasmModule,
    internal val machineFactory: Function<Instance, Machine>?,
    /** Where it came from, for messages. */
    public val origin: String,
    /** What runs its code. */
    public val engine: FirmwareEngine = FirmwareEngine.CHICORY,
) {
    /**
     * Whether robots may share an engine: true unless the code changes tables or data segments, state an engine
     * does not swap between robots. The compiled image carries no code to look at; it is the firmware, built by clang
     * from C, which never does (FirmwareEngineTest checks its wasm).
     */
    internal val sharesEngines: Boolean = !changesTablesOrSegments(module)

    private val engines = ThreadLocal.withInitial { ChicoryEngine(this) }

    /** This thread's engine (for an image whose robots may share one). */
    internal fun engine(): ChicoryEngine = engines.get()

    /** After a call failed: the engine may be in the middle of something, the thread's next call builds a new one. */
    internal fun discardEngine() = engines.remove()

    private class Fresh(val memory: ByteArray, val globals: LongArray)

    /** A fresh Chicory instance's memory and mutable globals, copied into every new robot it runs. */
    private val fresh: Fresh by lazy {
        val engine = ChicoryEngine(this)
        if (sharesEngines) engines.set(engine) // this thread's engine: [ChicoryEngine.enter] loads a robot's state into it
        Fresh(engine.memory.bytes.copyOf(), engine.initialGlobals())
    }
    internal val initialMemory: ByteArray get() = fresh.memory
    internal val initialGlobals: LongArray get() = fresh.globals

    /** A robot's firmware, fresh: not yet started (sim_init). */
    internal fun instantiate(): FirmwareInstance = when (engine) {
        FirmwareEngine.NATIVE -> NativeFirmware()
        FirmwareEngine.CHICORY -> ChicoryFirmware(this)
    }

    public companion object {
        private const val COMPILED_CLASS = "org.pocketbot.emulator.firmware.FirmwareModule"
        private const val COMPILED_HCI_CLASS = "org.pocketbot.emulator.firmware.HciFirmwareModule"

        /** The wasm the compiled class was made from, which the native engine must have been built from too. */
        private const val COMPILED_WASM = "pocketbot.wasm"

        /** `-Dpocketbot.emulator.engine=native|chicory` picks the engine of [compiled]; without it, native if it can. */
        public const val ENGINE_PROPERTY: String = "pocketbot.emulator.engine"

        private val logger = System.getLogger("org.pocketbot.emulator")
        private val reported = HashSet<String>()

        /**
         * The firmware as the emulator was built with it (firmware/build/wasm/pocketbot.wasm), run by [engine], or by
         * `-Dpocketbot.emulator.engine`, or else natively when the native engine loads and was built from the same
         * wasm, and by Chicory (the wasm compiled to JVM bytecode at build time) otherwise. Says which engine runs,
         * and why not the native one, once per JVM (`System.Logger` "org.pocketbot.emulator", INFO).
         *
         * Throws [IllegalStateException] when the emulator was built without the firmware (run `make -C firmware
         * wasm`, then rebuild the emulator), or when [FirmwareEngine.NATIVE] is asked for and cannot run.
         *
         * Under Chicory, logs a warning (once) when the JVM was started without `-XX:-DontCompileHugeMethods`:
         * HotSpot then never compiles the firmware's largest functions, and the emulator runs at about half its speed
         * (emulator/README.md, "Performance").
         */
        @JvmOverloads
        public fun compiled(engine: FirmwareEngine? = null): FirmwareImage = compiled(COMPILED_CLASS, COMPILED_WASM, engine)

        /**
         * The HCI build of the firmware (firmware/build/wasm/pocketbot-hci.wasm, compiled at build time like
         * [compiled]): its UART carries H4 to a Bluetooth controller and hosts reach it over Bluetooth
         * (see [org.pocketbot.emulator.RobotHandle.attachH4]). Runs on Chicory: the native engine is built from the
         * serial firmware only. Throws [IllegalStateException] when the emulator was built without it.
         */
        public fun compiledHci(): FirmwareImage = compiled(COMPILED_HCI_CLASS, "pocketbot-hci.wasm", null)

        private fun compiled(className: String, wasm: String, engine: FirmwareEngine?): FirmwareImage {
            val cls = try {
                Class.forName(className)
            } catch (e: ClassNotFoundException) {
                throw IllegalStateException(
                    "the emulator was built without firmware/build/wasm/$wasm: run `make -C firmware wasm`, then rebuild the emulator", e,
                )
            }
            val module = cls.getMethod("load").invoke(null) as WasmModule
            val create = cls.getMethod("create", Instance::class.java)
            val machines = Function<Instance, Machine> { instance -> create.invoke(null, instance) as Machine }
            val nativeBuilt = wasm == COMPILED_WASM // the native engine is built from that firmware only
            val wanted = if (!nativeBuilt) FirmwareEngine.CHICORY else engine ?: System.getProperty(ENGINE_PROPERTY)?.let { name ->
                FirmwareEngine.entries.firstOrNull { it.name.equals(name, ignoreCase = true) }
                    ?: throw IllegalArgumentException("-D$ENGINE_PROPERTY=$name: not one of native, chicory")
            }
            val why = if (wanted == FirmwareEngine.CHICORY) null else whyNotNative
            val chosen = when {
                wanted == FirmwareEngine.CHICORY -> FirmwareEngine.CHICORY
                why == null -> FirmwareEngine.NATIVE
                wanted == FirmwareEngine.NATIVE -> throw IllegalStateException("the native firmware engine cannot run: $why")
                else -> FirmwareEngine.CHICORY
            }
            report(when {
                chosen == FirmwareEngine.NATIVE -> "the firmware runs natively (${(NativeEngine.status as NativeEngine.Loaded).from})"
                !nativeBuilt -> "the firmware $wasm runs on Chicory (the native engine is built from $COMPILED_WASM only)"
                why == null -> "the firmware runs on Chicory, as asked"
                else -> "the firmware runs on Chicory (JVM bytecode), not natively: $why"
            })
            if (chosen == FirmwareEngine.CHICORY) hugeMethodsChecked
            return FirmwareImage(module, machines, "compiled:$className", chosen)
        }

        /** Why the native engine cannot run the compiled firmware; null when it can. Found out once per JVM. */
        private val whyNotNative: String? by lazy {
            val library = when (val s = NativeEngine.status) {
                is NativeEngine.Unavailable -> return@lazy "the native engine ${s.reason}"
                is NativeEngine.Loaded -> s
            }
            val wasm = FirmwareImage::class.java.getResourceAsStream(COMPILED_WASM)?.use { it.readBytes() }
                ?: return@lazy "the emulator's jar lacks the firmware's wasm to check the native engine against"
            val sha = MessageDigest.getInstance("SHA-256").digest(wasm).joinToString("") { "%02x".format(it) }
            if (sha != library.wasmSha256) {
                return@lazy "${library.from} was built from another firmware (wasm SHA-256 ${library.wasmSha256.take(12)}, " +
                    "this emulator's ${sha.take(12)}): rebuild both with make"
            }
            // What the native engine's build leaves out (firmware/Makefile): growing memory.
            if (growsMemory(Parser.parse(wasm))) "the firmware can grow its memory, which the native engine does not do" else null
        }

        internal fun growsMemory(module: WasmModule): Boolean =
            module.codeSection().functionBodies().any { body -> body.instructions().any { it.opcode() == OpCode.MEMORY_GROW } }

        private fun report(message: String) {
            if (synchronized(reported) { reported.add(message) }) logger.log(System.Logger.Level.INFO, "PocketBot emulator: $message")
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
