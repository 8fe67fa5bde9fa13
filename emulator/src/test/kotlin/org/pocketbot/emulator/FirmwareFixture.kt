package org.pocketbot.emulator

import org.pocketbot.emulator.firmware.FirmwareEngine
import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.emulator.world.Worlds
import kotlin.math.PI
import kotlin.math.atan2
import kotlin.math.hypot

/**
 * The real firmware (firmware/build/wasm/pocketbot.wasm, compiled to bytecode at build time, and natively by
 * `make -C firmware native-engine`), shared by tests: [image] as users get it (native where it runs), or either engine.
 */
object RealFirmware {
    val image: FirmwareImage by lazy { compiled(null) }
    val native: FirmwareImage by lazy { compiled(FirmwareEngine.NATIVE) }
    val chicory: FirmwareImage by lazy { compiled(FirmwareEngine.CHICORY) }

    private fun compiled(engine: FirmwareEngine?): FirmwareImage {
        check(FirmwareImage.compiledAvailable()) {
            "the emulator tests run the real firmware: run `make -C firmware wasm native-engine`, then rebuild the emulator"
        }
        return FirmwareImage.compiled(engine)
    }

    fun emulator(world: String, seed: Long = 1): Emulator =
        Emulator(Worlds.load(world), EmulatorConfig(seed = seed, firmware = image))
}

/** Normalises an angle in degrees to -180..180. */
fun wrapDeg(a: Double): Double { var x = a % 360.0; if (x > 180) x -= 360.0; if (x < -180) x += 360.0; return x }

fun polarAngle(x: Double, y: Double, cx: Double, cy: Double): Double = atan2(y - cy, x - cx)

fun radius(x: Double, y: Double, cx: Double, cy: Double): Double = hypot(x - cx, y - cy)

fun unwrap(prev: Double, next: Double): Double { var d = next - prev; while (d > PI) d -= 2 * PI; while (d < -PI) d += 2 * PI; return d }
