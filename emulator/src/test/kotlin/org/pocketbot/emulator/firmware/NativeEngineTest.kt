package org.pocketbot.emulator.firmware

import com.dylibso.chicory.wasm.Parser
import org.pocketbot.emulator.RealFirmware
import java.io.File
import java.util.concurrent.TimeUnit
import kotlin.test.Test
import kotlin.test.assertContains
import kotlin.test.assertContentEquals
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertTrue

/**
 * The native engine (firmware/native/engine.c): each robot's firmware an instance of its own, isolated from the
 * others, exactly as Chicory runs it; traps and closed instances end in exceptions, not in a crashed JVM; and the
 * emulator says which engine runs, falling back to Chicory when the library is missing.
 */
class NativeEngineTest {
    /** A robot's firmware with the same sensor inputs as every other: what differs is its id and its history. */
    private fun still(image: FirmwareImage) = image.instantiate().apply {
        setLineSensorModel(300.0, 110.0, 1790.0, 6.0)
        for (s in 0 until 10) setSensor(s, if (s == SimSensor.BATTERY_MV) 3900.0 else 20.0)
        setNoise(true, 42)
    }

    private fun FirmwareInstance.bytes() = memory.readBytes(0, memory.size)

    /** [ms] milliseconds of a robot with host bytes now and then (the same for every robot given the same [byte]). */
    private fun FirmwareInstance.run(ms: IntRange, byte: Int, offset: Long = 0) {
        for (t in ms) {
            advance(t * TICKS_PER_MS + offset)
            if (t % 100 == 0) uartRx(byte)
        }
    }

    @Test
    fun `the shipped firmware runs natively where the build made the library`() {
        assertEquals(FirmwareEngine.NATIVE, RealFirmware.image.engine, "the default engine on ${NativeEngine.platform()}")
        assertFalse(FirmwareImage.growsMemory(Parser.parse(shippedWasm())))
    }

    @Test
    fun `each robot's native memory is its own, and ends exactly as under Chicory`() {
        val a = still(RealFirmware.native)
        val b = still(RealFirmware.native)
        a.init(1)
        b.init(2)
        for (ms in 1..1500) { // b's firmware runs between every two calls of a's, on the same thread
            a.run(ms..ms, 0xC0)
            b.run(ms..ms, 0x00, offset = 17)
        }
        val alone = still(RealFirmware.native).apply { init(1); run(1..1500, 0xC0) }
        val chicory = still(RealFirmware.chicory).apply { init(1); run(1..1500, 0xC0) }
        assertContentEquals(alone.bytes(), a.bytes(), "robot 1's memory, with robot 2 run in between")
        assertContentEquals(chicory.bytes(), a.bytes(), "robot 1's memory under Chicory")
        assertEquals(chicory.noiseState(), a.noiseState(), "the noise stream the sensors drew from")
        assertFalse(a.bytes().contentEquals(b.bytes()), "robot 2 ran on robot 1's memory")
        // A new robot starts from a fresh instance's memory, the same under both engines.
        assertContentEquals(RealFirmware.chicory.initialMemory, RealFirmware.native.instantiate().bytes())
    }

    @Test
    fun `a firmware whose memory was scribbled over traps, under either engine, and the others run on`() {
        for (image in listOf(RealFirmware.native, RealFirmware.chicory)) {
            val hit = still(image).apply { init(1); run(1..100, 0xC0) }
            val other = still(image).apply { init(2); run(1..100, 0xC0) }
            // Every byte above the stack: pointers and the scheduler's function indices now point nowhere.
            hit.memory.write(STACK_BYTES, ByteArray(hit.memory.size - STACK_BYTES) { -1 })
            val trap = assertFailsWith<RuntimeException>("${image.engine}") { hit.run(101..200, 0xC0) }
            println("${image.engine}: ${trap.message}")
            other.run(101..200, 0xC0)
            val alone = still(image).apply { init(2); run(1..200, 0xC0) }
            assertContentEquals(alone.bytes(), other.bytes(), "${image.engine}: the other robot after the trap")
        }
    }

    @Test
    fun `a closed native instance refuses calls instead of touching freed memory`() {
        val fw = still(RealFirmware.native).apply { init(1); run(1..10, 0xC0) }
        fw.close()
        assertFailsWith<IllegalStateException> { fw.advance(11 * TICKS_PER_MS) }
        assertFailsWith<IndexOutOfBoundsException> { fw.pwmLeft() }
        fw.close() // twice is harmless
    }

    @Test
    fun `firmware that could grow its memory is not for the native engine`() {
        // (func (drop (memory.grow (i32.const 1)))) with a memory, and the same function without the grow.
        val grows = wasm("010401600000 03020100 0503010001 0a09010700410140001a0b")
        val stays = wasm("010401600000 03020100 0503010001 0a040102000b")
        assertTrue(FirmwareImage.growsMemory(Parser.parse(grows)))
        assertFalse(FirmwareImage.growsMemory(Parser.parse(stays)))
    }

    @Test
    fun `without its library the emulator runs the firmware on Chicory and says why`() {
        val missing = probe("-D${NativeEngine.LIBRARY_PROPERTY}=/no/such/libpocketbot-firmware.so")
        assertContains(missing.out, "engine=CHICORY")
        assertContains(missing.err, "the firmware runs on Chicory (JVM bytecode), not natively: the native engine " +
            "-D${NativeEngine.LIBRARY_PROPERTY}=/no/such/libpocketbot-firmware.so is no file")
        val junk = File.createTempFile("not-a-library", ".so").apply { writeText("not a shared object"); deleteOnExit() }
        val asked = probe("-D${NativeEngine.LIBRARY_PROPERTY}=$junk", "-D${FirmwareImage.ENGINE_PROPERTY}=native")
        assertContains(asked.out, "error=the native firmware engine cannot run: the native engine $junk does not load")
        val chicory = probe("-D${FirmwareImage.ENGINE_PROPERTY}=chicory")
        assertContains(chicory.out, "engine=CHICORY")
        assertContains(probe().out, "engine=NATIVE", message = "a JVM with the library")
    }

    private class Probe(val out: String, val err: String)

    /** [EngineProbe] in a JVM of its own (the library loads once per JVM), with [options]. */
    private fun probe(vararg options: String): Probe {
        val java = File(System.getProperty("java.home"), "bin/java").path
        val process = ProcessBuilder(listOf(java, "-cp", System.getProperty("java.class.path")) + options + EngineProbe::class.java.name)
            .start()
        process.outputStream.close()
        val err = StringBuilder()
        val errReader = Thread { err.append(process.errorStream.bufferedReader().readText()) }.apply { start() }
        val out = process.inputStream.bufferedReader().readText()
        assertTrue(process.waitFor(60, TimeUnit.SECONDS), "the probe did not end")
        errReader.join()
        return Probe(out, err.toString())
    }

    private fun shippedWasm(): ByteArray = FirmwareImage::class.java.getResourceAsStream("pocketbot.wasm")!!.readBytes()

    /** A module from the hex of its sections (spaces ignored), after the wasm header. */
    private fun wasm(sections: String): ByteArray =
        ("0061736d01000000" + sections.replace(" ", "")).chunked(2).map { it.toInt(16).toByte() }.toByteArray()

    private companion object {
        const val TICKS_PER_MS = 32_000L
        /** The firmware's stack (--stack-first, 16 KiB) lies below its data. */
        const val STACK_BYTES = 16384
    }
}

/** Prints the engine the compiled firmware runs on in this JVM (`engine=...`), or why it cannot (`error=...`). */
object EngineProbe {
    @JvmStatic
    fun main(args: Array<String>) {
        try {
            println("engine=${FirmwareImage.compiled().engine}")
        } catch (e: IllegalStateException) {
            println("error=${e.message}")
        }
    }
}
