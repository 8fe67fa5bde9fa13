package org.pocketbot.emulator

import org.pocketbot.emulator.firmware.FirmwareImage
import org.pocketbot.emulator.firmware.FirmwareInstance
import org.pocketbot.emulator.firmware.SimSensor
import org.pocketbot.emulator.link.RobotLink
import org.pocketbot.emulator.link.RobotLinks
import org.pocketbot.emulator.physics.Obb
import org.pocketbot.emulator.physics.RobotParams
import org.pocketbot.sdk.Pose
import kotlin.math.PI
import kotlin.math.abs
import kotlin.math.cos
import kotlin.math.exp
import kotlin.math.floor
import kotlin.math.sin

/**
 * One simulated PocketBot2: its body and motors, its sensors, and its own firmware instance.
 * Everything here runs on the emulator's stepping threads; users read it through [RobotHandle].
 */
internal class SimRobot(
    val id: Int,
    val index: Int,
    val params: RobotParams,
    private val world: SimWorld,
    image: FirmwareImage,
    start: Pose,
    seed: Long,
    @Volatile var noise: NoiseSettings,
) {
    // Pose of the axle midpoint; the body is centred on it.
    var x = start.xM
    var y = start.yM
    var theta = start.headingRad

    /** Ground speed of each wheel (m/s), the wheels' total travel (m, signed), and the motors' duty (-1..1). */
    var vl = 0.0; var vr = 0.0
    var distL = 0.0; var distR = 0.0
    var dutyL = 0.0; var dutyR = 0.0
    var led = 0

    // Streams per robot (by its place in the fleet: ids repeat in fleets over 254), fixed by the seed.
    // The sensor stream is the firmware's too: its simulation HAL draws each reading's noise from it (sim_inputs_t).
    private val sensorRng = SplitMix64(seed * 0x9E3779B97F4A7C15uL.toLong() + index * 0x2545F491L + id)
    private val linkSeed = seed * 31 + index * 0x5DEECE66DL + id * 7919L + 7

    private val encPhaseL = sensorRng.nextDouble() * params.stripePairM
    private val encPhaseR = sensorRng.nextDouble() * params.stripePairM
    private val alpha = 1 - exp(-SimTime.STEP_S / params.motorTauS)

    // Battery and temperature.
    private var chargeUsedMah = 0.0
    var currentMa = params.idleCurrentMa; private set
    private var prevV = 0.0
    private var accelXmg = 0.0
    private var accelYmg = 0.0

    // Line sensor spots and the colour under the colour sensor, once per step (see sense()).
    private val spotDark = DoubleArray(8)
    private val spotX = DoubleArray(8)
    private val spotY = DoubleArray(8)
    private val colourRgb = DoubleArray(3)

    // Box contact found at the end of the previous step.
    var contactBox = -1
    var pushDirX = 0.0; var pushDirY = 0.0

    // IR messages sent during the step (delivered by SimWorld at the step's end) and received for the next step.
    var irOutCount = 0
    val irOutLed = IntArray(IR_CAP); val irOutPower = IntArray(IR_CAP); val irOutLen = IntArray(IR_CAP)
    val irOutLo = IntArray(IR_CAP); val irOutHi = IntArray(IR_CAP); val irOutSender = IntArray(IR_CAP)
    private var irInCount = 0
    private val irIn = IntArray(IR_CAP * 7)
    var irDropped = 0L; private set

    val scratchObb = Obb()
    val scratchOverlap = DoubleArray(3)
    private val edgeTimes = LongArray(16)
    private val edgeWheels = IntArray(16)
    private val txBuf = ByteArray(RobotLink.MAX_TAKE)
    private var txSteps = 0

    private val image = image
    var firmware: FirmwareInstance = image.instantiate(); private set

    /** The robot's host links, as many as its firmware serves. */
    val links = RobotLinks(firmware.linkCount, linkSeed)
    /** Link 0, the UART: the only one of a robot with one host. */
    val link: RobotLink get() = links.all[0]
    /** Bit k: the firmware has link k open (it opens the UART at reset; the others when a host comes). */
    private var firmwareLinks = 1

    /** Set by the emulator while a step defers this robot to the serial contact phase. */
    var deferred = false

    /** Set by [SimWorld.markAlone] while nothing can reach this robot for a block of steps. */
    var alone = false

    /** Emulator time of sim_init: the firmware counts its ticks from there. */
    var bootTicks = 0L; private set

    fun bootAt(now: Long) {
        bootTicks = now
        val fw = firmware
        fw.setLineSensorModel(world.ambientAdc.toDouble(), params.lineSignalWhiteAdc, params.lineSignalBlackAdc - params.lineSignalWhiteAdc, params.lineNoiseAdc)
        sense(fw)
        fw.init(id)
        fw.advance(0)
        afterFirmware(fw)
        readOutputs()
    }

    /** A power cycle: a fresh firmware instance (nothing of the old RAM survives) with the old one's EEPROM. */
    fun reset(now: Long) {
        val eeprom = firmware.eeprom()
        firmware.close()
        firmware = image.instantiate()
        if (eeprom != null) firmware.loadEeprom(eeprom)
        irInCount = 0
        // The fresh firmware has only its UART open; a robot's reset drops its other links (as a Bluetooth robot's
        // does), so their hosts reconnect and hear that it restarted.
        firmwareLinks = 1
        for (l in links.all) if (l.index > 0) l.dropConnection("the robot was reset")
        bootAt(now)
    }

    /** Moves the robot (a hand placing it); the wheels stop. */
    fun place(pose: Pose) {
        x = pose.xM; y = pose.yM; theta = pose.headingRad
        vl = 0.0; vr = 0.0; prevV = 0.0; contactBox = -1
    }

    // ---- phase 1: motors --------------------------------------------------------------------------------------

    fun motorUpdate() {
        val vScale = batteryLoadedV() / params.nominalBatteryV
        val v0 = params.noLoadSpeedMps
        vl += (v0 * dutyL * vScale - vl) * alpha
        vr += (v0 * dutyR * vScale - vr) * alpha
    }

    /** Stall force along the heading the motors make at their current duty (both wheels). */
    fun driveForceN(): Double = params.stallForcePerWheelN * batteryLoadedV() / params.nominalBatteryV * (dutyL + dutyR)

    val forwardSpeed: Double get() = (vl + vr) / 2

    /** Limits the forward speed (a box or a wall in front), keeping the turn rate. */
    fun limitForwardSpeed(max: Double) {
        val excess = forwardSpeed - max
        if (excess > 0) { vl -= excess; vr -= excess }
    }

    // ---- phase 2: move, then run the firmware through the step ------------------------------------------------

    fun moveAndRun(t0: Long, t1: Long) {
        val dt = SimTime.STEP_S
        val dL = vl * dt
        val dR = vr * dt
        var gL = dL; var gR = dR
        if (noise.wheelSlip > 0) {
            gL *= 1 - noise.wheelSlip * sensorRng.nextDouble()
            gR *= 1 - noise.wheelSlip * sensorRng.nextDouble()
        }
        val ds = (gL + gR) / 2
        val dTheta = (gR - gL) / params.wheelBaseM
        val mid = theta + dTheta / 2
        x += ds * cos(mid); y += ds * sin(mid)
        theta += dTheta
        if (theta > PI) theta -= 2 * PI else if (theta < -PI) theta += 2 * PI

        val v = ds / dt
        accelXmg = (v - prevV) / dt / G * 1000
        accelYmg = v * (dTheta / dt) / G * 1000
        prevV = v

        // Encoder edges of both wheels, in time order.
        var nEdges = collectEdges(0, distL + encPhaseL, distL + dL + encPhaseL, t0, 0)
        nEdges = collectEdges(1, distR + encPhaseR, distR + dR + encPhaseR, t0, nEdges)
        distL += dL; distR += dR
        for (i in 1 until nEdges) { // insertion sort, a handful at most
            val t = edgeTimes[i]; val w = edgeWheels[i]; var j = i - 1
            while (j >= 0 && edgeTimes[j] > t) { edgeTimes[j + 1] = edgeTimes[j]; edgeWheels[j + 1] = edgeWheels[j]; j-- }
            edgeTimes[j + 1] = t; edgeWheels[j + 1] = w
        }
        val fw = firmware
        sense(fw)
        // IR heard at the end of the previous step.
        if (irInCount > 0) {
            for (k in 0 until irInCount) {
                val o = k * 7
                fw.irRx(irIn[o], irIn[o + 1], irIn[o + 2], irIn[o + 3], irIn[o + 4], irIn[o + 5], irIn[o + 6])
            }
            irInCount = 0
        }
        // Host bytes and encoder edges at their own times, merged in time order and handed over in one batch; hosts that
        // came first, hosts that left last (after their last byte).
        val hostLinks = activeLinks()
        var queued = 0
        for (k in 0 until hostLinks) {
            val l = links.all[k]
            if (l.takeOpen()) { fw.putEvent(queued++, t0 - bootTicks, FirmwareInstance.EVENT_LINK_OPEN, k); firmwareLinks = firmwareLinks or (1 shl k) }
            l.scheduleHostBytes(t0)
        }
        var e = 0
        while (true) {
            val te = if (e < nEdges) edgeTimes[e] else Long.MAX_VALUE
            var rx = link
            for (k in 1 until hostLinks) if (links.all[k].nextRxTime() < rx.nextRxTime()) rx = links.all[k]
            val tr = rx.nextRxTime()
            if (tr < t1 && tr <= te) {
                val k = rx.index
                if (k == 0) fw.putEvent(queued++, tr - bootTicks, FirmwareInstance.EVENT_UART_RX, rx.popRx())
                else fw.putEvent(queued++, tr - bootTicks, FirmwareInstance.EVENT_LINK_RX, k shl 8 or rx.popRx())
            } else if (te <= t1) {
                fw.putEvent(queued++, te - bootTicks, FirmwareInstance.EVENT_ENCODER_EDGE, edgeWheels[e]); e++
            } else break
            if (queued == FirmwareInstance.EVENT_CAPACITY) { fw.runEvents(queued, -1); queued = 0 }
        }
        for (k in 0 until hostLinks) {
            if (queued == FirmwareInstance.EVENT_CAPACITY) { fw.runEvents(queued, -1); queued = 0 }
            if (links.all[k].takeClose()) { fw.putEvent(queued++, t1 - bootTicks, FirmwareInstance.EVENT_LINK_CLOSE, k); firmwareLinks = firmwareLinks and (1 shl k).inv() }
        }
        fw.runEvents(queued, t1 - bootTicks)
        readOutputs()

        // Each link drains at the baud rate. A link without a host sends its bytes nowhere, so it is enough to drain
        // it every few steps (saving a call into the firmware per step); the firmware sees the same rate.
        txSteps++
        val idleDrain = txSteps >= IDLE_TX_STEPS
        if (idleDrain) txSteps = 0
        for (k in 0 until hostLinks) {
            val l = links.all[k]
            val allowance = l.txAllowance(t1 - t0)
            if (allowance > 0 && (firmwareLinks and (1 shl k)) != 0 && (idleDrain || l.isAttached)) {
                val n = fw.linkTxTake(k, allowance)
                if (n > 0) {
                    val mem = fw.memory
                    val base = fw.txBufferAddress
                    for (i in 0 until n) txBuf[i] = mem.read(base + i)
                    l.robotSent(txBuf, n, t0)
                }
            }
            l.deliverToHost(t1)
        }
        afterFirmware(fw)

        updateBattery(dt)
        world.checkContacts(this)
    }

    /** How many links (from link 0) a step must look at: beyond the UART only while another link has a host or is open. */
    private fun activeLinks(): Int {
        val all = links.all
        for (k in all.size - 1 downTo 1) if (all[k].isAttached || (firmwareLinks and (1 shl k)) != 0 || all[k].pending) return k + 1
        return 1
    }

    private fun collectEdges(wheel: Int, u0: Double, u1: Double, t0: Long, start: Int): Int {
        if (u0 == u1) return start
        var n = start
        val p = params.stripePairM
        val b = params.blackStripeShare * p
        val e0 = edgeIndex(u0, p, b)
        val e1 = edgeIndex(u1, p, b)
        val span = u1 - u0
        if (e1 > e0) {
            var k = e0 + 1
            while (k <= e1 && n < edgeTimes.size) { edgeTimes[n] = t0 + edgeTicks(edgePos(k, p, b) - u0, span); edgeWheels[n] = wheel; n++; k++ }
        } else if (e0 > e1) {
            var k = e0
            while (k > e1 && n < edgeTimes.size) { edgeTimes[n] = t0 + edgeTicks(edgePos(k, p, b) - u0, span); edgeWheels[n] = wheel; n++; k-- }
        }
        return n
    }

    private fun edgeTicks(part: Double, span: Double): Long {
        val f = (part / span).coerceIn(0.0, 1.0)
        return Math.round(f * SimTime.STEP_TICKS).coerceAtLeast(1L)
    }

    private fun readOutputs() {
        dutyL = clamp(firmware.pwmLeft(), -1000, 1000) / 1000.0
        dutyR = clamp(firmware.pwmRight(), -1000, 1000) / 1000.0
        led = firmware.led()
    }

    // ---- power ----------------------------------------------------------------------------------------------

    private fun batteryOpenV(): Double {
        val soc = (1 - chargeUsedMah / params.batteryCapacityMah).coerceIn(0.0, 1.0)
        return params.batteryEmptyV + (params.batteryFullV - params.batteryEmptyV) * soc
    }

    fun batteryLoadedV(): Double = batteryOpenV() - currentMa / 1000 * params.batteryInternalOhm

    private fun updateBattery(dt: Double) {
        val v0 = params.noLoadSpeedMps
        val iL = abs(dutyL - vl / v0).coerceAtMost(1.0) * params.motorStallCurrentMa
        val iR = abs(dutyR - vr / v0).coerceAtMost(1.0) * params.motorStallCurrentMa
        currentMa = params.idleCurrentMa + iL + iR
        chargeUsedMah += currentMa * dt / 3600
    }

    // ---- what the firmware's sensors face, and the IR it sends ---------------------------------------------------

    /**
     * Writes what the sensors face now into the firmware's memory (sim_abi.h sim_inputs_t), where its simulation HAL
     * reads them, adding noise from this robot's sensor stream: once per step instead of a call out of the firmware
     * per conversion. The robot does not move while its firmware runs, so every reading in the step is as it was.
     */
    private fun sense(fw: FirmwareInstance) {
        computeSpots()
        for (j in 0 until 8) fw.setLineDark(j, spotDark[j])
        val a = params.colourSensorAheadM
        world.surface.colourAt(x + a * cos(theta), y + a * sin(theta), params.colourSpotRadiusM, colourRgb)
        fw.setSensor(SimSensor.BATTERY_MV, batteryLoadedV() * 1000)
        fw.setSensor(SimSensor.CURRENT_MA, currentMa)
        fw.setSensor(SimSensor.MCU_TEMP_DC, 250 + currentMa / 20)
        fw.setSensor(SimSensor.ACCEL_X_MG, accelXmg)
        fw.setSensor(SimSensor.ACCEL_Y_MG, accelYmg)
        fw.setSensor(SimSensor.ACCEL_Z_MG, 1000.0)
        fw.setSensor(SimSensor.COLOUR_R, colourRgb[0])
        fw.setSensor(SimSensor.COLOUR_G, colourRgb[1])
        fw.setSensor(SimSensor.COLOUR_B, colourRgb[2])
        fw.setSensor(SimSensor.COLOUR_CLEAR, (colourRgb[0] + colourRgb[1] + colourRgb[2]) / 3)
        fw.setNoise(noise.sensorNoise, sensorRng.state)
    }

    private fun computeSpots() {
        val c = cos(theta); val s = sin(theta)
        val a = params.lineSensorAheadM
        for (j in 0 until 8) {
            val lat = (3.5 - j) * params.lineSpotPitchM // spot 0 is the leftmost (+y in the robot frame)
            spotX[j] = x + a * c - lat * s
            spotY[j] = y + a * s + lat * c
        }
        world.surface.irDarknessSpots(spotX, spotY, 8, params.lineSpotRadiusM, spotDark)
    }

    /** After the firmware's calls of a step: the noise it drew, and the IR messages it sent (delivered by SimWorld). */
    private fun afterFirmware(fw: FirmwareInstance) {
        sensorRng.state = fw.noiseState()
        val sent = fw.irOutCount()
        for (m in 0 until sent) {
            if (irOutCount == IR_CAP) { irDropped++; continue }
            val k = irOutCount++
            irOutSender[k] = fw.irOut(m, FirmwareInstance.IR_SENDER); irOutLed[k] = fw.irOut(m, FirmwareInstance.IR_LED)
            irOutPower[k] = clamp(fw.irOut(m, FirmwareInstance.IR_POWER), 0, 100)
            irOutLen[k] = clamp(fw.irOut(m, FirmwareInstance.IR_LEN), 0, 8)
            irOutLo[k] = fw.irOut(m, FirmwareInstance.IR_PAYLOAD_LO); irOutHi[k] = fw.irOut(m, FirmwareInstance.IR_PAYLOAD_HI)
        }
        irDropped += fw.clearIrOut()
    }

    /** Queues an IR reception for the start of the next step (called by SimWorld, serially). */
    fun irHeard(side: Int, sender: Int, led: Int, power: Int, len: Int, lo: Int, hi: Int) {
        if (irInCount == IR_CAP) { irDropped++; return }
        val o = irInCount++ * 7
        irIn[o] = side; irIn[o + 1] = sender; irIn[o + 2] = led; irIn[o + 3] = power
        irIn[o + 4] = len; irIn[o + 5] = lo; irIn[o + 6] = hi
    }

    /** Moved by a collision (not by its wheels). */
    fun shove(dx: Double, dy: Double) { x += dx; y += dy }

    /** The robot's body as an oriented box. */
    fun body(out: Obb) = out.set(x, y, theta, params.lengthM / 2, params.widthM / 2)

    companion object {
        const val IR_CAP = 32
        const val IDLE_TX_STEPS = 8
        const val G = 9.80665

        /** [v] within [lo]..[hi]: Kotlin's `coerceIn` is not inlined and showed in the profile from these calls. */
        private fun clamp(v: Int, lo: Int, hi: Int): Int = if (v < lo) lo else if (v > hi) hi else v

        fun edgeIndex(u: Double, pair: Double, black: Double): Long {
            val k = floor(u / pair)
            val frac = u - k * pair
            return k.toLong() * 2 + if (frac >= black) 1 else 0
        }

        fun edgePos(n: Long, pair: Double, black: Double): Double =
            Math.floorDiv(n, 2L) * pair + if (Math.floorMod(n, 2L) == 1L) black else 0.0
    }
}

/** Which random effects are on. Sensor noise is deterministic from the seed; slip is off by default. */
public class NoiseSettings(
    public val sensorNoise: Boolean = true,
    /** Up to this fraction of each wheel's travel is lost to slip (random per step), 0 = no slip. */
    public val wheelSlip: Double = 0.0,
)
