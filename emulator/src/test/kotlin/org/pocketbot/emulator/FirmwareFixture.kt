package org.pocketbot.emulator

import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.emulator.world.Worlds
import kotlin.math.PI
import kotlin.math.atan2
import kotlin.math.hypot

/** The real firmware (firmware/build/wasm/pocketbot.wasm, compiled to bytecode at build time), shared by tests. */
object RealFirmware {
    val image: FirmwareImage by lazy {
        check(FirmwareImage.compiledAvailable()) {
            "the emulator tests run the real firmware: run `make -C firmware wasm`, then rebuild the emulator"
        }
        FirmwareImage.compiled()
    }

    fun emulator(world: String, seed: Long = 1): Emulator =
        Emulator(Worlds.load(world), EmulatorConfig(seed = seed, firmware = image))
}

/** Normalises an angle in degrees to -180..180. */
fun wrapDeg(a: Double): Double { var x = a % 360.0; if (x > 180) x -= 360.0; if (x < -180) x += 360.0; return x }

fun polarAngle(x: Double, y: Double, cx: Double, cy: Double): Double = atan2(y - cy, x - cx)

fun radius(x: Double, y: Double, cx: Double, cy: Double): Double = hypot(x - cx, y - cy)

fun unwrap(prev: Double, next: Double): Double { var d = next - prev; while (d > PI) d -= 2 * PI; while (d < -PI) d += 2 * PI; return d }
