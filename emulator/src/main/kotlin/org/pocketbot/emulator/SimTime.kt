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
    public fun fromDuration(d: Duration): Long = d.inWholeNanoseconds * TICKS_PER_SECOND / 1_000_000_000L
}
