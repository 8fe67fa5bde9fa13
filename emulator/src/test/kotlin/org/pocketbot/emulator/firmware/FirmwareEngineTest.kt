package org.pocketbot.emulator.firmware

import org.pocketbot.emulator.RealFirmware
import kotlin.test.Test
import kotlin.test.assertContentEquals
import kotlin.test.assertFalse
import kotlin.test.assertTrue

/**
 * Robots whose firmware runs in turn in one [FirmwareEngine] (one Chicory instance per thread): each robot's firmware
 * must be exactly what it would be with the engine to itself.
 */
class FirmwareEngineTest {
    /** The same inputs for every robot: what differs between two robots here is their id and their history. */
    private object Still : FirmwareHost {
        override fun lineAdcSweep(emitters: Int): Long = 0x0100_0100_0100_0100L
        override fun sensorRead(sensor: Int): Int = if (sensor == SimSensor.BATTERY_MV) 3900 else 20
        override fun irSend(senderId: Int, led: Int, power: Int, len: Int, payloadLo: Int, payloadHi: Int) = Unit
    }

    @Test
    fun theShippedFirmwareLetsRobotsShareAnEngine() {
        // An engine swaps memory and globals, not tables or dropped data segments: code that changes those would
        // need an engine per robot. The firmware is C built by clang, which emits none of it.
        assertTrue(RealFirmware.image.sharesEngines)
    }

    @Test
    fun robotsInterleavedOnOneEngineEachEndAsTheyWouldAlone() {
        val image = RealFirmware.image
        val a = FirmwareInstance(image, Still)
        val b = FirmwareInstance(image, Still)
        a.init(1)
        b.init(2)
        // b's firmware is called between every two calls of a's, on this thread's one engine.
        for (ms in 1..1500) {
            a.advance(ms * TICKS_PER_MS)
            b.advance(ms * TICKS_PER_MS + 17)
            if (ms % 100 == 0) { a.uartRx(0xC0); b.uartRx(0x00) }
        }
        val alone = FirmwareInstance(image, Still)
        alone.init(1)
        for (ms in 1..1500) {
            alone.advance(ms * TICKS_PER_MS)
            if (ms % 100 == 0) alone.uartRx(0xC0)
        }
        assertContentEquals(alone.linear.bytes, a.linear.bytes, "robot 1's memory")
        assertContentEquals(alone.globals, a.globals, "robot 1's globals (the stack pointer)")
        assertFalse(a.linear.bytes.contentEquals(b.linear.bytes), "robot 2 ran on robot 1's memory")
        // A new robot starts from the image's fresh memory, not from what the engine ran last.
        assertContentEquals(image.initialMemory, FirmwareInstance(image, Still).linear.bytes)
    }

    private companion object {
        const val TICKS_PER_MS = 32_000L
    }
}
