package org.pocketbot.emulator

import kotlin.time.Duration
import kotlin.time.Duration.Companion.nanoseconds

/** Simulated time: 32 MHz MCU clock ticks since the emulator started (as the firmware counts them). */
public object SimTime {
    public const val TICKS_PER_SECOND: Long = 32_000_000L
    /** One emulator step: 1 ms, the firmware's main loop period. */
    public const val STEP_TICKS: Long = 32_000L
    public const val STEP_S: Double = STEP_TICKS.toDouble() / TICKS_PER_SECOND

    public fun toDuration(ticks: Long): Duration = (ticks * 1_000_000_000.0 / TICKS_PER_SECOND).toLong().nanoseconds
    /** Whole ticks in [d] (rounded down). Exact for any duration: ns x 32e6 would overflow a Long past 288 s. */
    public fun fromDuration(d: Duration): Long {
        val ns = d.inWholeNanoseconds
        return ns / NS_PER_TICK_DEN * TICKS_PER_NS_NUM + ns % NS_PER_TICK_DEN * TICKS_PER_NS_NUM / NS_PER_TICK_DEN
    }

    // ticks = ns * 32e6 / 1e9 = ns * 4 / 125, with the fraction reduced so the product cannot overflow.
    private const val TICKS_PER_NS_NUM = 4L
    private const val NS_PER_TICK_DEN = 125L
}
