package org.pocketbot.sdk


/**
 * One value of [RobotState] by its dotted name in the protocol (`wheels.speed_left_mmps`), for tools that print,
 * log or pick state values by name (the command line's `state --fields`, CSV logs). Enum values read as their
 * lower-case names, flags as the names of the bits set joined by `+` (`-` for none), the line sensor's spots as a list.
 */
public class StateField internal constructor(
    public val name: String,
    public val unit: String,
    /**
     * The most characters the value takes as text: the widest number of its wire type (`-32768` for an i16), its
     * longest name, the line sensor's eight spots with spaces between. A table of streamed states aligns on it.
     */
    public val width: Int,
    private val read: (RobotState) -> Any,
) {
    /** This field's value in [state]. */
    public fun of(state: RobotState): Any = read(state)

    override fun toString(): String = name
}

/** Every field of [RobotState], in struct order. */
public object StateFields {
    public val all: List<StateField> = buildList {
        fun f(name: String, width: Int, unit: String = "", read: (RobotState) -> Any) = add(StateField(name, unit, width, read))
        fun side(prefix: String, pick: (RobotState) -> RobotState.ProximitySide) {
            f("$prefix.flags", flags(ProximityFlag.entries)) { flagsText(pick(it).flags) }
            f("$prefix.robot_id", U8) { pick(it).robotId }
            f("$prefix.robot_led", names(IrLed.entries)) { pick(it).robotLed.name.lowercase() }
            f("$prefix.distance", names(DistanceClass.entries)) { pick(it).distance.name.lowercase() }
        }
        f("time.time_ms", U32, "ms") { it.time.timeMs }
        f("time.tick_max_us", U16, "us") { it.time.tickMaxUs }
        f("time.overruns", U16) { it.time.overruns }
        f("time.last_overrun_ms", U32, "ms") { it.time.lastOverrunMs }
        f("encoders.left", I32, "pulses") { it.encoders.left }
        f("encoders.right", I32, "pulses") { it.encoders.right }
        f("wheels.speed_left_mmps", I16, "mm/s") { it.wheels.speedLeftMmps }
        f("wheels.speed_right_mmps", I16, "mm/s") { it.wheels.speedRightMmps }
        f("wheels.pwm_left", I16, "permille") { it.wheels.pwmLeft }
        f("wheels.pwm_right", I16, "permille") { it.wheels.pwmRight }
        f("line.raw", LINE_SPOTS * (U16 + 1) - 1, "adc") { it.line.raw }
        f("line.position", I16, "permille") { it.line.position }
        f("line.flags", flags(LineFlag.entries)) { flagsText(it.line.flags) }
        f("line_follow.status", names(LineFollowStatus.entries)) { it.lineFollow.status.name.lowercase() }
        f("line_follow.segment", names(Colour.entries)) { it.lineFollow.segment.name.lowercase() }
        side("proximity.front") { it.proximity.front }
        side("proximity.rear") { it.proximity.rear }
        f("colour.red", U8) { it.colour.red }
        f("colour.green", U8) { it.colour.green }
        f("colour.blue", U8) { it.colour.blue }
        f("colour.clear", U8) { it.colour.clear }
        f("colour.detected", names(Colour.entries)) { it.colour.detected.name.lowercase() }
        f("accel.x_mg", I16, "mg") { it.accel.xMg }
        f("accel.y_mg", I16, "mg") { it.accel.yMg }
        f("accel.z_mg", I16, "mg") { it.accel.zMg }
        f("power.battery_mv", U16, "mV") { it.power.batteryMv }
        f("power.current_ma", U16, "mA") { it.power.currentMa }
        f("power.mcu_temp_dc", I16, "0.1 degC") { it.power.mcuTempDc }
        f("indicators.led", flags(LedFlag.entries)) { flagsText(it.indicators.led) }
        f("indicators.ir_power", U8, "percent") { it.indicators.irPower }
        f("locomotion.mode", names(LocoMode.entries)) { it.locomotion.mode.name.lowercase() }
        f("locomotion.queue_length", U8) { it.locomotion.queueLength }
        f("locomotion.current_id", U16) { it.locomotion.currentId }
        f("locomotion.finished_id", U16) { it.locomotion.finishedId }
        f("track.status", names(TrackStatus.entries)) { it.track.status.name.lowercase() }
        f("track.token", U8) { it.track.token }
        f("track.token_visits", U16) { it.track.tokenVisits }
        f("track.met_id", U8) { it.track.metId }
        f("errors.crc", U16) { it.errors.crc }
        f("errors.framing", U16) { it.errors.framing }
        f("errors.rejected", U16) { it.errors.rejected }
        f("errors.rx_overflow", U16) { it.errors.rxOverflow }
        f("errors.tx_dropped", U16) { it.errors.txDropped }
        f("errors.bt_wire", U16) { it.errors.btWire }
        f("errors.bt_timeouts", U16) { it.errors.btTimeouts }
        f("errors.bt_resets", U16) { it.errors.btResets }
        f("errors.bt_dropped", U16) { it.errors.btDropped }
    }

    /**
     * The fields called [names]; a name may also be a group (`wheels`: every `wheels.*` field).
     * @throws IllegalArgumentException naming the first name that is no field or group.
     */
    public fun select(names: List<String>): List<StateField> = names.flatMap { n ->
        all.filter { it.name == n || it.name.startsWith("$n.") }
            .ifEmpty { throw IllegalArgumentException("no state field '$n' (groups: ${all.map { it.name.substringBefore('.') }.distinct().joinToString()})") }
    }
}

// The widest text of each wire type: 255, 65535, -32768, 4294967295, -2147483648.
private const val U8 = 3
private const val U16 = 5
private const val I16 = 6
private const val U32 = 10
private const val I32 = 11
private const val LINE_SPOTS = 8

private fun names(entries: List<Enum<*>>): Int = entries.maxOf { it.name.length }

// A flags field reads as its set bits' names joined by '+' (`seen+lost`), `-` when none is set.
private fun flags(entries: List<Enum<*>>): Int = entries.sumOf { it.name.length + 1 } - 1

private fun flagsText(set: Set<Enum<*>>): String = if (set.isEmpty()) "-" else set.joinToString("+") { it.name.lowercase() }
