package org.pocketbot.sdk

/**
 * What this host asks to be on a robot ([RobotOptions.role], [Robot.setRole]). One host drives a robot; the others
 * watch it: they get its state, debug text and movement results, may read its settings and may stop it, but the
 * robot refuses whatever else they send ([NotDriverException]).
 */
public enum class Role {
    /** Watch only: never take the drive. */
    WATCH,

    /** Drive if no other host does; else watch, and drive as soon as the driver leaves (the robot hands it over). */
    DRIVE,

    /** Drive, taking the robot from the host that drives it (which is told, and watches from then on). */
    TAKE_OVER,
}

/** Why the host that drives a robot changed, as the robot said. */
public enum class DriverChange {
    /** Nothing changed: the robot answered a question (the handshake, a refused command). */
    NONE,

    /** A host began to drive a robot that no host drove. */
    CLAIMED,

    /** A host took the robot over from the host that drove it. */
    TAKEN_OVER,

    /** The driver left: it said goodbye, or asked to watch. */
    LEFT,

    /** Nothing came from the driver for the robot's failsafe timeout: its link is lost, and another host drives now. */
    LOST,
}

/**
 * Who drives a robot, as the robot last told this host ([Robot.driving]).
 *
 * @property byThisHost true while this host drives it.
 * @property driver the label of the host that drives it (`panel@lab-pc`; this host's own when [byThisHost]), or
 *   null when no host drives it.
 * @property change why it last changed.
 */
public class Driving internal constructor(
    public val byThisHost: Boolean,
    public val driver: String?,
    public val change: DriverChange,
) {
    override fun equals(other: Any?): Boolean =
        other is Driving && byThisHost == other.byThisHost && driver == other.driver && change == other.change

    override fun hashCode(): Int = (byThisHost.hashCode() * 31 + driver.hashCode()) * 31 + change.hashCode()

    override fun toString(): String = when {
        byThisHost -> "driven by this host ($driver)"
        driver != null -> "driven by $driver"
        else -> "driven by no host"
    }

    internal companion object {
        /** Before the robot said anything. */
        val UNKNOWN = Driving(false, null, DriverChange.NONE)
    }
}

/** What the robot does with this host's queued movements when this host leaves as the driver ([Robot.disconnect]). */
public enum class QueueOnLeave {
    /** The queued movements run to their end (teleoperation stops; line following goes on if it is autonomous). */
    FINISH,

    /** They are dropped, as by a stop: the running movement brakes along its profile. */
    DROP,
}

/** Something that happened to a robot, which a face shows to its user ([Robot.events]). */
public sealed class RobotEvent {
    /**
     * The host that drives the robot changed. [taken] is true when this host drove it and another one took it over
     * (or got it after this host fell silent); [driving] says who drives now.
     */
    public class DriverChanged internal constructor(public val driving: Driving, public val taken: Boolean) : RobotEvent() {
        override fun toString(): String = "DriverChanged($driving${if (taken) ", taken from this host" else ""})"
    }

    /**
     * The robot restarted: its clock went back from [lastSeenTimeMs] (the latest this host saw) to [timeMs]. Its
     * queue, its movement log and its encoder counts started afresh; every movement it no longer knows ended as
     * [MovementOutcome.LOST], with how much of it this host saw done.
     */
    public class Restarted internal constructor(public val lastSeenTimeMs: Long, public val timeMs: Long) : RobotEvent() {
        override fun toString(): String = "Restarted(robot time $lastSeenTimeMs ms -> $timeMs ms)"
    }
}
