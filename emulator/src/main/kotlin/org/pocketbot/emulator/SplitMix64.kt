package org.pocketbot.emulator

/**
 * The generator of [java.util.SplittableRandom] (the same numbers from the same seed), with its state in the open: a
 * robot's sensor noise is one stream that the emulator and the firmware's simulation HAL draw from in turn, the HAL
 * from the state the emulator writes into the firmware's memory each step (firmware/hal/sim/sim_abi.h, sim_inputs_t).
 */
internal class SplitMix64(var state: Long) {
    fun nextLong(): Long {
        state += GOLDEN_GAMMA
        var z = state
        z = (z xor (z ushr 30)) * -0x40a7b892e31b1a47L // 0xBF58476D1CE4E5B9
        z = (z xor (z ushr 27)) * -0x6b2fb644ecceee15L // 0x94D049BB133111EB
        return z xor (z ushr 31)
    }

    /** Uniform in [0, 1), as SplittableRandom.nextDouble(). */
    fun nextDouble(): Double = (nextLong() ushr 11) * DOUBLE_UNIT

    private companion object {
        const val GOLDEN_GAMMA = -0x61c8864680b583ebL // 0x9E3779B97F4A7C15
        const val DOUBLE_UNIT = 1.0 / (1L shl 53)
    }
}
