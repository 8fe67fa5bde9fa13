package org.pocketbot.sdk

import kotlinx.coroutines.CoroutineDispatcher
import kotlinx.coroutines.Dispatchers
import kotlin.coroutines.AbstractCoroutineContextElement
import kotlin.coroutines.CoroutineContext
import kotlin.random.Random

/**
 * How the SDK runs its own work for the robots connected in a scope: reading their links, heartbeats, supervision
 * and reconnects run on [dispatcher] (one coroutine at a time per robot), and its random choices (the host session
 * id, the first movement id) come from [random].
 *
 * Without this element in the scope's context the SDK uses [Dispatchers.Default] and [Random.Default], never the
 * caller's dispatcher, so user code that blocks its thread cannot starve a link. The emulator's simulated time puts
 * its own runtime here, so that the SDK's clock is the simulation's and a run repeats exactly.
 *
 * ```
 * val robot = device.connect(scope + RobotRuntime(myDispatcher))
 * ```
 */
public class RobotRuntime(
    public val dispatcher: CoroutineDispatcher,
    public val random: Random = Random.Default,
) : AbstractCoroutineContextElement(Key) {
    /** The key of this element in a [CoroutineContext]. */
    public companion object Key : CoroutineContext.Key<RobotRuntime>

    override fun toString(): String = "RobotRuntime($dispatcher)"
}
