package org.pocketbot.android.model

import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.launch
import org.pocketbot.sdk.LineCalibration
import org.pocketbot.sdk.LineCalibrator
import org.pocketbot.sdk.Robot

/** Where a calibration stands: one step of the calibration screen. */
sealed class CalibrationStep {
    /** Nothing running: the robot's calibration now is [current]. */
    data class Ready(val current: LineCalibration) : CalibrationStep()

    /** The robot sweeps over the line; [progress] 0..1, the readings so far. */
    data class Sweeping(val progress: Double, val white: List<Int>, val black: List<Int>) : CalibrationStep()

    /** By hand: waiting for the user to put the robot on white. */
    data object PlaceOnWhite : CalibrationStep()

    /** By hand: white was read; waiting for the robot on black (all spots on the tape). */
    data class PlaceOnBlack(val white: List<Int>) : CalibrationStep()

    /** Reading the spots while the robot stands still. */
    data class Sampling(val what: String) : CalibrationStep()

    /** A result to look at before writing it: usable or not ([LineCalibration.weakSpots]). */
    data class Measured(val calibration: LineCalibration) : CalibrationStep()

    /** Writing it to the robot, each setting waiting for its acknowledgement. */
    data class Writing(val calibration: LineCalibration) : CalibrationStep()

    /** The robot acknowledged it and uses it; not yet in its EEPROM. */
    data class Written(val calibration: LineCalibration) : CalibrationStep()

    /** Saved in the robot's EEPROM: it survives a reset. */
    data class Saved(val calibration: LineCalibration) : CalibrationStep()

    /** It went wrong; [message] says why. */
    data class Failed(val message: String) : CalibrationStep()
}

/**
 * The calibration screen's logic over the SDK's [LineCalibrator]: a sweep, or white then black by hand; the result
 * per spot; writing it (acknowledged) and saving it to EEPROM when the user confirms.
 */
class CalibrationModel(
    private val robot: Robot,
    private val scope: CoroutineScope,
    private val act: (String, suspend () -> Unit) -> Unit,
) {
    private val calibrator = LineCalibrator(robot)
    private val _step = MutableStateFlow<CalibrationStep>(CalibrationStep.Ready(LineCalibration.of(robot)))
    private var job: Job? = null

    val step: StateFlow<CalibrationStep> = _step.asStateFlow()

    /** The robot turns left and right over the line it stands on. */
    fun sweep() = run {
        val progress = scope.launch {
            calibrator.progress.collect { p -> if (p != null) _step.value = CalibrationStep.Sweeping(p.fraction, p.white, p.black) }
        }
        try {
            _step.value = CalibrationStep.Sweeping(0.0, emptyList(), emptyList())
            CalibrationStep.Measured(calibrator.sweep())
        } finally {
            progress.cancel()
        }
    }

    /** Calibrating by hand: the user is asked for white first. */
    fun byHand() {
        if (job?.isActive == true) return
        _step.value = CalibrationStep.PlaceOnWhite
    }

    /** The robot stands where the step asked: read the spots. */
    fun sampleHere() {
        when (val step = _step.value) {
            CalibrationStep.PlaceOnWhite -> run {
                _step.value = CalibrationStep.Sampling("white")
                CalibrationStep.PlaceOnBlack(calibrator.sample())
            }
            is CalibrationStep.PlaceOnBlack -> run {
                _step.value = CalibrationStep.Sampling("black")
                CalibrationStep.Measured(LineCalibration(step.white, calibrator.sample()))
            }
            else -> {}
        }
    }

    /** Writes the measured calibration to the robot. */
    fun write() {
        val measured = (_step.value as? CalibrationStep.Measured)?.calibration ?: return
        if (!measured.isUsable) return
        run {
            _step.value = CalibrationStep.Writing(measured)
            calibrator.apply(measured)
            CalibrationStep.Written(measured)
        }
    }

    /** The user confirmed: the written calibration goes to the robot's EEPROM. */
    fun save() {
        val written = (_step.value as? CalibrationStep.Written)?.calibration ?: return
        run {
            calibrator.save()
            CalibrationStep.Saved(written)
        }
    }

    /** Back to the start, showing the robot's calibration. */
    fun reset() {
        if (job?.isActive == true) {
            job?.cancel()
            act("stop the sweep") { robot.locomotion.stop() } // a sweep's turn may be running; a failure is told
        }
        _step.value = CalibrationStep.Ready(LineCalibration.of(robot))
    }

    private fun run(block: suspend () -> CalibrationStep) {
        if (job?.isActive == true) return
        job = scope.launch {
            _step.value = try {
                block()
            } catch (e: CancellationException) {
                throw e
            } catch (e: Exception) {
                CalibrationStep.Failed(failure(e))
            }
        }
    }
}
