package org.pocketbot.sdk

import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.protocol.LoadDefaults
import org.pocketbot.protocol.ReadSettings
import org.pocketbot.protocol.SETTINGS_DEFAULTS
import org.pocketbot.protocol.SETTINGS_FIELDS
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.protocol.Settings
import org.pocketbot.protocol.SettingsFieldInfo
import org.pocketbot.protocol.UpdateSettings
import org.pocketbot.sdk.internal.SettingsJson
import org.pocketbot.sdk.internal.settingsOf

/**
 * Settings reflection (thesis 6.3, 9.6): a typed tree of every field of the robot's settings struct, mirrored on
 * the host. Each field writes itself alone:
 *
 * ```
 * robot.settings.linePid.kp.set(1.5f)          // sends 4 bytes at offset 70, suspends until acknowledged
 * val kp = robot.settings.linePid.kp.value     // the confirmed value
 * robot.settings.save()                         // to EEPROM
 * ```
 */
public class RobotSettings internal constructor(private val robot: Robot) {
    private val byPath = LinkedHashMap<String, SettingField<*>>()
    private val _values = MutableStateFlow(SETTINGS_DEFAULTS)

    private fun info(path: String): SettingsFieldInfo =
        SETTINGS_FIELDS.firstOrNull { it.path == path } ?: error("the protocol has no setting $path")

    private fun <F : SettingField<*>> reg(f: F): F = f.also { byPath[it.path] = it }
    internal fun float(path: String): FloatSetting = reg(FloatSetting(robot, info(path)))
    internal fun int(path: String): IntSetting = reg(IntSetting(robot, info(path)))
    internal fun ints(path: String): IntListSetting = reg(IntListSetting(robot, info(path)))
    internal fun text(path: String): TextSetting = reg(TextSetting(robot, info(path)))

    /** Who the robot is. */
    public val identity: IdentitySettings = IdentitySettings(this)

    /** State reflection defaults (prefer [Robot.reflector], which also keeps them across reconnects). */
    public val sync: SyncSettings = SyncSettings(this)

    /** Main loop timing. */
    public val scheduler: SchedulerSettings = SchedulerSettings(this)

    /** Robot speed PID: speed error (m/s) -> motor PWM (permille). */
    public val speedPid: PidSettings = PidSettings(this, "speed_pid")

    /** Per-wheel speed PID (line following, teleoperation): wheel speed error (m/s) -> PWM (permille). */
    public val wheelPid: PidSettings = PidSettings(this, "wheel_pid")

    /** Wheel balance: keeps the left:right distance ratio; error in metres -> PWM correction (permille). */
    public val wheelBalance: PidSettings = PidSettings(this, "wheel_balance")

    /** Line following PD: line position (permille) -> wheel speed difference (m/s). */
    public val linePid: PidSettings = PidSettings(this, "line_pid")

    /** Three-segment speed profile of movements. */
    public val profile: ProfileSettings = ProfileSettings(this)

    /** Line following speeds and behaviour. */
    public val lineFollow: LineFollowSettings = LineFollowSettings(this)

    /** Line sensor calibration. */
    public val lineSensor: LineSensorSettings = LineSensorSettings(this)

    /** Wheel encoders. */
    public val encoder: EncoderSettings = EncoderSettings(this)

    /** Robot geometry (used by locomotion and [Odometry]). */
    public val geometry: GeometrySettings = GeometrySettings(this)

    /** Motor drive limits. */
    public val motors: MotorSettings = MotorSettings(this)

    /** IR proximity. */
    public val proximity: ProximitySettings = ProximitySettings(this)

    /** Host link supervision. */
    public val link: LinkSettings = LinkSettings(this)

    /** Debug text sent to the host. */
    public val debug: DebugSettings = DebugSettings(this)

    /** Every field, in struct order. */
    public val fields: List<SettingField<*>> = byPath.values.sortedBy { it.info.offset }

    init {
        val missing = SETTINGS_FIELDS.map { it.path }.filter { it !in byPath }
        check(missing.isEmpty()) { "settings tree lacks $missing" }
    }

    /** The field at dotted [path] (e.g. `line_pid.kp`), or null. */
    public fun field(path: String): SettingField<*>? = byPath[path]

    /** The whole settings struct as the robot confirmed it, updated on every acknowledged change. */
    public val values: StateFlow<Settings> = _values.asStateFlow()

    internal fun mirrorChanged(bytes: ByteArray) {
        _values.value = settingsOf(bytes)
    }

    /** Reads the whole settings struct from the robot again (`read_settings`), updating every field. */
    public suspend fun readAll(): Settings {
        robot.readSettings { robot.command(ReadSettings) }
        return values.value
    }

    /** Saves the robot's current settings to its EEPROM, so they survive a reset. */
    public suspend fun save() {
        robot.command(SaveSettings)
    }

    /** Replaces the robot's settings with its compiled-in defaults (not saved until [save]) and reads them back. */
    public suspend fun loadDefaults() {
        robot.command(LoadDefaults)
        readAll()
    }

    /**
     * All settings as JSON, grouped as in the protocol definition:
     * `{"identity": {"robot_id": 1, "name": "PocketBot"}, "speed_pid": {"kp": 2500.0, ...}, ...}`.
     */
    public fun exportJson(): String = SettingsJson.export(robot.settingsBytes)

    /**
     * Writes every setting in [json] (the format of [exportJson]; fields may be left out) whose value differs from
     * the robot's, contiguous fields together in one `update_settings` of at most 64 bytes. Suspends until all are
     * acknowledged; returns the number of fields written.
     *
     * @throws IllegalArgumentException for malformed JSON, an unknown field or a value of the wrong type.
     * @throws SettingRefusedException when the robot refuses a value (writes before it stay written).
     */
    public suspend fun importJson(json: String): Int {
        val wanted = SettingsJson.parse(json, robot.settingsBytes)
        val current = robot.serial { robot.settingsBytes.copyOf() }
        val changed = SETTINGS_FIELDS.filter { f ->
            (f.offset until f.offset + f.size).any { wanted[it] != current[it] }
        }
        for (run in SettingsJson.runs(changed)) {
            val start = run.first().offset
            val end = run.last().offset + run.last().size
            val data = wanted.copyOfRange(start, end)
            try {
                robot.command(UpdateSettings(start, data))
            } catch (e: CommandRefusedException) {
                val culprit = run.firstOrNull { it.offset == e.detail } ?: run.first()
                throw SettingRefusedException(
                    if (run.size == 1) culprit.path else run.joinToString(",") { it.path }, null, e.packetType, e.rawCode, e.detail,
                )
            }
            robot.serial { robot.settingsWritten(start, data) }
        }
        return changed.size
    }
}

/** Who the robot is. */
public class IdentitySettings internal constructor(s: RobotSettings) {
    /** Unique id 1..254, also sent in IR messages. */
    public val robotId: IntSetting = s.int("identity.robot_id")

    /** User-friendly name, at most 16 UTF-8 bytes. */
    public val name: TextSetting = s.text("identity.name")
}

/** What the robot sends on its own and how often (stored defaults of the reflector). */
public class SyncSettings internal constructor(s: RobotSettings) {
    /** 0 none, 1 full, 2 reduced (see [org.pocketbot.protocol.SyncMode]). */
    public val mode: IntSetting = s.int("sync.mode")

    /** Period of state packets, 1..60000 ms. */
    public val periodMs: IntSetting = s.int("sync.period_ms")
}

/** Main loop timing. */
public class SchedulerSettings internal constructor(s: RobotSettings) {
    /** Period of the main loop tick, 500..20000 us. */
    public val mainPeriodUs: IntSetting = s.int("scheduler.main_period_us")
}

/** Gains of a discrete PID controller: u = kp*e + ki*sum(e) + kd*(e - e_prev), the sum clamped to +-iLimit. */
public class PidSettings internal constructor(s: RobotSettings, prefix: String) {
    /** Proportional gain. */
    public val kp: FloatSetting = s.float("$prefix.kp")

    /** Integral gain (per tick). */
    public val ki: FloatSetting = s.float("$prefix.ki")

    /** Derivative gain (per tick). */
    public val kd: FloatSetting = s.float("$prefix.kd")

    /** Clamp of the integral sum, in error units x ticks. */
    public val iLimit: FloatSetting = s.float("$prefix.i_limit")
}

/** Three-segment speed profile of movements: accelerate, cruise, brake. */
public class ProfileSettings internal constructor(s: RobotSettings) {
    /** Acceleration slope, m/s^2. */
    public val accelMps2: FloatSetting = s.float("profile.accel_mps2")

    /** Braking slope, m/s^2. */
    public val decelMps2: FloatSetting = s.float("profile.decel_mps2")

    /** Speed at start and end of the profile, m/s. */
    public val minSpeedMps: FloatSetting = s.float("profile.min_speed_mps")
}

/** Line following speeds and behaviour. */
public class LineFollowSettings internal constructor(s: RobotSettings) {
    /** Cruise speed on black line, m/s. */
    public val speedMps: FloatSetting = s.float("line_follow.speed_mps")

    /** Speed on red segments (colour mode), m/s. */
    public val redSpeedMps: FloatSetting = s.float("line_follow.red_speed_mps")

    /** Speed on blue segments (colour mode), m/s. */
    public val blueSpeedMps: FloatSetting = s.float("line_follow.blue_speed_mps")

    /** Stop after the line was lost this long, ms. */
    public val lostTimeoutMs: IntSetting = s.int("line_follow.lost_timeout_ms")

    /** 1: keep following when the host link is lost. */
    public val autonomous: IntSetting = s.int("line_follow.autonomous")
}

/** Line sensor calibration: per-spot ambient-suppressed readings of white (min) and black (max). */
public class LineSensorSettings internal constructor(s: RobotSettings) {
    /** Reading over white per spot, adc. */
    public val calMin: IntListSetting = s.ints("line_sensor.cal_min")

    /** Reading over black per spot, adc. */
    public val calMax: IntListSetting = s.ints("line_sensor.cal_max")

    /** Calibrated darkness above which a spot sees the line, permille. */
    public val threshold: IntSetting = s.int("line_sensor.threshold")
}

/** Wheel encoders and speed measurement. */
public class EncoderSettings internal constructor(s: RobotSettings) {
    /** Encoder pulses per wheel revolution. */
    public val pulsesPerRev: IntSetting = s.int("encoder.pulses_per_rev")

    /** Speed reads zero after no pulse this long, ms. */
    public val speedTimeoutMs: IntSetting = s.int("encoder.speed_timeout_ms")
}

/** Robot geometry, used by locomotion and host odometry. */
public class GeometrySettings internal constructor(s: RobotSettings) {
    /** Wheel diameter, m. */
    public val wheelDiameterM: FloatSetting = s.float("geometry.wheel_diameter_m")

    /** Distance between the wheels (gauge), m. */
    public val wheelBaseM: FloatSetting = s.float("geometry.wheel_base_m")
}

/** Motor drive limits. */
public class MotorSettings internal constructor(s: RobotSettings) {
    /** Largest PWM duty the controllers may command, permille. */
    public val pwmLimit: IntSetting = s.int("motors.pwm_limit")
}

/** IR proximity: beacons to other robots and obstacle detection. */
public class ProximitySettings internal constructor(s: RobotSettings) {
    /** Highest beacon power, percent; 0 turns the beacon off. */
    public val irPower: IntSetting = s.int("proximity.ir_power")

    /** Period of IR beacons, ms. */
    public val beaconPeriodMs: IntSetting = s.int("proximity.beacon_period_ms")

    /** How long a sighting stays in the state, ms. */
    public val holdMs: IntSetting = s.int("proximity.hold_ms")
}

/** Host link supervision. */
public class LinkSettings internal constructor(s: RobotSettings) {
    /** Stop host-driven motion after this long without a packet, ms; 0 = off. */
    public val failsafeTimeoutMs: IntSetting = s.int("link.failsafe_timeout_ms")
}

/** Debug text sent to the host. */
public class DebugSettings internal constructor(s: RobotSettings) {
    /** 0 off, 1 errors, 2 info, 3 verbose, 4 trace. */
    public val level: IntSetting = s.int("debug.level")
}
