package org.pocketbot.emulator.firmware

import com.dylibso.chicory.wasm.Parser
import org.pocketbot.emulator.RealFirmware
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertFalse
import kotlin.test.assertTrue

/**
 * Robots whose firmware runs in turn in one [ChicoryEngine] (one Chicory instance per thread): each robot's firmware
 * must be exactly what it would be with the engine to itself.
 */
class ChicoryEngineTest {
    /** The same sensor inputs for every robot: what differs between two robots here is their id and their history. */
    private fun still(image: FirmwareImage) = (image.instantiate() as ChicoryFirmware).apply {
        setLineSensorModel(300.0, 110.0, 1790.0, 6.0)
        for (s in 0 until 10) setSensor(s, if (s == SimSensor.BATTERY_MV) 3900.0 else 20.0)
        setNoise(true, 42)
    }

    @Test
    fun theShippedFirmwareLetsRobotsShareAnEngine() {
        // An engine swaps memory and globals, not tables or dropped data segments: code that changes those would
        // need an engine per robot. The firmware is C built by clang, which emits none of it. (The compiled image
        // carries no code to look at: its wasm does, beside it in the jar.)
        assertTrue(RealFirmware.chicory.sharesEngines)
        val wasm = FirmwareImage::class.java.getResourceAsStream("pocketbot.wasm")!!.readBytes()
        assertFalse(FirmwareImage.changesTablesOrSegments(Parser.parse(wasm)))
    }

    @Test
    fun robotsInterleavedOnOneEngineEachEndAsTheyWouldAlone() {
        val image = RealFirmware.chicory
        val a = still(image)
        val b = still(image)
        a.init(1)
        b.init(2)
        // b's firmware is called between every two calls of a's, on this thread's one engine.
        for (ms in 1..1500) {
            a.advance(ms * TICKS_PER_MS)
            b.advance(ms * TICKS_PER_MS + 17)
            if (ms % 100 == 0) { a.uartRx(0xC0); b.uartRx(0x00) }
        }
        val alone = still(image)
        alone.init(1)
        for (ms in 1..1500) {
            alone.advance(ms * TICKS_PER_MS)
            if (ms % 100 == 0) alone.uartRx(0xC0)
        }
        assertContentEquals(alone.linear.bytes, a.linear.bytes, "robot 1's memory")
        assertContentEquals(alone.globals, a.globals, "robot 1's globals (the stack pointer)")
        assertFalse(a.linear.bytes.contentEquals(b.linear.bytes), "robot 2 ran on robot 1's memory")
        // A new robot starts from the image's fresh memory, not from what the engine ran last.
        assertContentEquals(image.initialMemory, (image.instantiate() as ChicoryFirmware).linear.bytes)
    }

    private companion object {
        const val TICKS_PER_MS = 32_000L
    }
}
