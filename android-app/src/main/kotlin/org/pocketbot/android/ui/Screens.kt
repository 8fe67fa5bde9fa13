package org.pocketbot.android.ui

import android.content.Context
import android.text.InputType
import android.view.Gravity
import android.view.View
import android.view.ViewGroup
import android.content.res.ColorStateList
import android.widget.CheckBox
import android.widget.EditText
import android.widget.LinearLayout
import android.widget.ProgressBar
import android.widget.RadioButton
import android.widget.RadioGroup
import android.widget.ScrollView
import android.widget.SeekBar
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.launch
import org.pocketbot.android.model.AppModel
import org.pocketbot.android.model.BluetoothStatus
import org.pocketbot.android.model.CalibrationStep
import org.pocketbot.android.model.JoystickModel
import org.pocketbot.android.model.RobotSession
import org.pocketbot.android.model.SpeedSetting
import org.pocketbot.android.model.Step
import org.pocketbot.sdk.Colour
import org.pocketbot.sdk.ColourMode
import org.pocketbot.sdk.LineCalibration
import org.pocketbot.sdk.LineFollowStatus

/** What the robot list asks the Activity to do about Bluetooth: the permission dialog, the switch, the settings. */
interface BluetoothActions {
    fun askPermission()
    fun openAppSettings()
    fun turnBluetoothOn()
}

private fun Context.scroll(vararg children: View): ScrollView = ScrollView(this).apply {
    isFillViewport = true
    addView(vertical(0, *children).apply { setPadding(0, dp(6), 0, dp(12)) })
}

/** A robot screen: the stale banner over [children], which scroll. */
private fun Context.robotScreen(session: RobotSession, scope: CoroutineScope, vararg children: View): View =
    scroll(staleBanner(scope, session.freshness), *children)

private fun Context.sliderRow(title: String, maxMps: Double, onRelease: (Double) -> Unit): Pair<LinearLayout, (SpeedSetting) -> Unit> {
    val label = text(title, 15f)
    val value = text("", 15f, palette.PRIMARY, bold = true).apply { gravity = Gravity.END }
    val status = text("", 12f, palette.TEXT_SOFT)
    val bar = SeekBar(this).apply {
        max = (maxMps * 100).toInt()
        contentDescription = title
        layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, dp(TOUCH_TARGET_DP))
    }
    bar.setOnSeekBarChangeListener(object : SeekBar.OnSeekBarChangeListener {
        override fun onProgressChanged(seekBar: SeekBar, progress: Int, fromUser: Boolean) {
            if (fromUser) value.text = settingMps(progress / 100.0)
        }
        override fun onStartTrackingTouch(seekBar: SeekBar) {}
        override fun onStopTrackingTouch(seekBar: SeekBar) = onRelease(seekBar.progress / 100.0)
    })
    val row = vertical(0, horizontal(label.apply { layoutParams = weight() }, value), bar, status).apply { setPadding(0, dp(6), 0, dp(6)) }
    return row to { s: SpeedSetting ->
        if (!s.pending) bar.progress = Math.round(s.mps * 100).toInt()
        value.text = settingMps(s.mps)
        status.text = when {
            s.pending -> "writing… waiting for the robot to acknowledge"
            s.refused != null -> "refused: ${s.refused}"
            else -> "acknowledged by the robot"
        }
        status.setTextColor(if (s.refused != null) palette.BAD else palette.TEXT_SOFT)
    }
}

/** A one-line text field that fills its row, labelled for screen readers by [hint]. */
private fun Context.field(value: String, hint: String): EditText = EditText(this).apply {
    setText(value)
    this.hint = hint
    inputType = InputType.TYPE_CLASS_TEXT or InputType.TYPE_TEXT_VARIATION_URI
    setSingleLine()
    textSize = 15f
    setTextColor(palette.TEXT)
    setHintTextColor(palette.TEXT_SOFT)
    minHeight = dp(TOUCH_TARGET_DP)
    layoutParams = weight()
}

/** Robots: Bluetooth's state and the way on, the robots found, an emulator on the network, the connected robot. */
fun robotsScreen(context: Context, model: AppModel, actions: BluetoothActions, scope: CoroutineScope): View = with(context) {
    val btText = text("", 14f)
    val btButton = button("", ButtonStyle.FILLED) {}
    val btCard = card("BLUETOOTH", btText, gap(10), btButton)
    val scanButton = button("Find robots", ButtonStyle.FILLED) { model.scan() }
    val progress = ProgressBar(this).apply {
        isIndeterminate = true
        contentDescription = "Searching"
        layoutParams = LinearLayout.LayoutParams(dp(28), dp(28))
    }
    val list = vertical(0)
    val empty = text("No robots found yet. Switch a robot on and tap Find robots.", 14f, palette.TEXT_SOFT)
    val everyDevice = CheckBox(this).apply {
        text = "Show all Bluetooth devices"
        textSize = 15f
        setTextColor(palette.TEXT)
        buttonTintList = ColorStateList.valueOf(palette.PRIMARY)
        minHeight = dp(TOUCH_TARGET_DP)
        isChecked = model.everyDevice.value
        setOnCheckedChangeListener { _, on -> model.showEveryDevice(on) }
    }
    val macField = field(model.bluetoothAddress.value, "Bluetooth address, e.g. 00:11:22:33:44:55")
    val foundCard = card(
        "ROBOTS NEARBY", horizontal(scanButton, gap(12), progress), gap(8), empty, list, everyDevice,
        text("A robot that is not listed: type its Bluetooth address.", 14f, palette.TEXT_SOFT),
        horizontal(macField, gap(8), button("Connect to address", ButtonStyle.OUTLINED) { model.connectBluetoothAddress(macField.text.toString()) }),
    )
    val address = field(model.emulatorAddress.value, "Emulator address, host:port")
    val emulatorCard = card(
        "EMULATOR ON THE NETWORK",
        text("No robot at hand? Drive an emulated one. On a computer on this Wi-Fi, serve the panel's emulator (World, " +
            "Serve on the network) or run pocketbot emulator --listen 0.0.0.0, then type the address it shows (host:port).",
            14f, palette.TEXT_SOFT),
        horizontal(address, gap(8), button("Find", ButtonStyle.OUTLINED) { model.findEmulator(address.text.toString()) }),
    )
    val connectedName = text("", 18f, bold = true)
    val connectedInfo = text("", 14f, palette.TEXT_SOFT)
    val connectedCard = card(
        "CONNECTED",
        connectedName, connectedInfo, gap(10),
        horizontal(button("Disconnect", ButtonStyle.OUTLINED) { model.disconnect() }),
    )

    scope.launch {
        model.bluetooth.status.collect { status ->
            btCard.visibility = if (status == BluetoothStatus.READY) View.GONE else View.VISIBLE
            btButton.visibility = View.VISIBLE
            when (status) {
                BluetoothStatus.READY -> {}
                BluetoothStatus.PERMISSION_NEEDED -> {
                    btText.text = "PocketBot finds and drives robots over Bluetooth. Android asks you to allow \"Nearby devices\" for that."
                    btButton.text = "Allow Bluetooth"
                    btButton.setOnClickListener { actions.askPermission() }
                }
                BluetoothStatus.PERMISSION_REFUSED -> {
                    btText.text = "Bluetooth permission refused: PocketBot cannot find or connect robots over Bluetooth. " +
                        "Allow it to drive a robot, or use an emulator below."
                    btButton.text = "Ask again"
                    btButton.setOnClickListener { actions.askPermission() }
                }
                BluetoothStatus.PERMISSION_BLOCKED -> {
                    btText.text = "Bluetooth permission refused: Android no longer asks. Allow \"Nearby devices\" in the app's " +
                        "settings (Permissions), or use an emulator below."
                    btButton.text = "Open settings"
                    btButton.setOnClickListener { actions.openAppSettings() }
                }
                BluetoothStatus.OFF -> {
                    btText.text = "Bluetooth is off. Turn it on to find robots."
                    btButton.text = "Turn Bluetooth on"
                    btButton.setOnClickListener { actions.turnBluetoothOn() }
                }
                BluetoothStatus.UNAVAILABLE -> {
                    btText.text = "This device has no Bluetooth. Drive an emulated robot over the network below."
                    btButton.visibility = View.GONE
                }
            }
        }
    }
    scope.launch { model.scanning.collect { progress.visibility = if (it) View.VISIBLE else View.INVISIBLE; scanButton.enabled(!it) } }
    scope.launch {
        combine(model.found, model.connecting, model.session) { found, connecting, session -> Triple(found, connecting, session) }.collect { (found, connecting, session) ->
            empty.visibility = if (found.isEmpty()) View.VISIBLE else View.GONE
            list.removeAllViews()
            for (robot in found) {
                val isConnected = session?.address == robot.address
                val action = when {
                    isConnected -> text("connected", 14f, palette.GOOD, bold = true)
                    connecting == robot.name -> ProgressBar(this@with).apply {
                        isIndeterminate = true
                        contentDescription = "Connecting"
                        layoutParams = LinearLayout.LayoutParams(dp(28), dp(28))
                    }
                    else -> button("Connect", ButtonStyle.FILLED) { model.connect(robot) }.apply { enabled(connecting == null) }
                }
                list.addView(horizontal(
                    vertical(0, text(robot.name, 17f, bold = true), text("${robot.source} · ${robot.address}", 12f, palette.TEXT_SOFT)).apply { layoutParams = weight() },
                    action,
                ).apply { setPadding(0, dp(10), 0, dp(10)) })
            }
            connectedCard.visibility = if (session != null) View.VISIBLE else View.GONE
            if (session != null) {
                connectedName.text = session.name
                val link = session.linkKind.value?.let { " · ${it.text}" } ?: ""
                connectedInfo.text = "${session.address}$link · firmware ${session.firmware}"
            }
        }
    }
    scroll(connectedCard, btCard, foundCard, emulatorCard)
}

/** Line sensor: the eight spots, the line position, seen or lost, live. */
fun sensorScreen(context: Context, session: RobotSession, scope: CoroutineScope): View = with(context) {
    val canvas = LineSensorCanvas(this)
    val seen = text("", 16f, bold = true)
    val position = text("", 15f)
    val legend = text("Darkness per spot (black = line; orange: above the threshold, red mark). Raw reading and darkness below each.", 13f, palette.TEXT_SOFT)
    scope.launch {
        combine(session.lineSensor.reading, session.freshness) { r, f -> r to f }.collect { (r, f) ->
            canvas.reading = r
            canvas.stale = !f.live
            seen.text = when {
                r.seen -> "● Line seen"
                r.lost -> "● Line lost"
                else -> "● No line under the sensor"
            }
            seen.setTextColor(palette.live(f, if (r.seen) palette.GOOD else if (r.lost) palette.BAD else palette.WARN))
            position.setTextColor(palette.live(f, palette.TEXT))
            position.text = if (r.seen) "Position ${r.position} ‰ (${if (r.position < -50) "left" else if (r.position > 50) "right" else "centred"})" else "Position: —"
        }
    }
    robotScreen(session, scope, card("LINE SENSOR", seen, position, gap(8), canvas, legend))
}

/** Calibration: a sweep over the line or white-then-black by hand, the result per spot, write, save. */
fun calibrationScreen(context: Context, session: RobotSession, scope: CoroutineScope): View = with(context) {
    val model = session.calibration
    val headline = text("", 17f, bold = true)
    val detail = text("", 14f, palette.TEXT_SOFT)
    val bar = ProgressBar(this, null, android.R.attr.progressBarStyleHorizontal).apply { max = 100 }
    val chart = CalibrationCanvas(this)
    val legend = text("Per spot: white (○) and black (●) readings in ADC counts, 1 = leftmost spot.", 13f, palette.TEXT_SOFT)
    val buttons = horizontal()
    fun setButtons(vararg b: View) {
        buttons.removeAllViews()
        b.forEachIndexed { i, v -> if (i > 0) buttons.addView(gap(8)); buttons.addView(v.apply { layoutParams = weight() }) }
    }
    scope.launch {
        model.step.collect { step ->
            bar.visibility = View.GONE
            chart.partial = null
            when (step) {
                is CalibrationStep.Ready -> {
                    headline.text = "Calibrate the line sensor"
                    detail.text = "Sweep: put the robot on the line, along it; it turns left and right in place so every spot sees " +
                        "the floor and the tape. By hand: you put it on white, then across black tape."
                    chart.calibration = step.current
                    setButtons(button("Sweep over the line") { model.sweep() }, button("By hand", ButtonStyle.OUTLINED) { model.byHand() })
                }
                is CalibrationStep.Sweeping -> {
                    headline.text = "Sweeping… ${(step.progress * 100).toInt()} %"
                    detail.text = "The robot turns over the line and records each spot's lightest and darkest reading."
                    bar.visibility = View.VISIBLE
                    bar.progress = (step.progress * 100).toInt()
                    chart.calibration = null
                    chart.partial = step.white to step.black
                    setButtons(button("Cancel", ButtonStyle.OUTLINED) { model.reset() })
                }
                CalibrationStep.PlaceOnWhite -> {
                    headline.text = "Step 1 of 2: white"
                    detail.text = "Put the robot on the white floor, away from any tape, then tap Read white."
                    setButtons(button("Read white") { model.sampleHere() }, button("Cancel", ButtonStyle.OUTLINED) { model.reset() })
                }
                is CalibrationStep.PlaceOnBlack -> {
                    headline.text = "Step 2 of 2: black"
                    detail.text = "Put the robot across the black tape so that all eight spots are on it, then tap Read black."
                    setButtons(button("Read black") { model.sampleHere() }, button("Cancel", ButtonStyle.OUTLINED) { model.reset() })
                }
                is CalibrationStep.Sampling -> {
                    headline.text = "Reading ${step.what}…"
                    detail.text = "Keep the robot still."
                    setButtons()
                }
                is CalibrationStep.Measured -> {
                    val c = step.calibration
                    chart.calibration = c
                    if (c.isUsable) {
                        headline.text = "Measured: every spot sees the line"
                        detail.text = "Contrast ${c.contrast.min()}–${c.contrast.max()} ADC counts. Write it to the robot to use it."
                        setButtons(button("Write to robot") { model.write() }, button("Discard", ButtonStyle.OUTLINED) { model.reset() })
                    } else {
                        headline.text = "Spots ${c.weakSpots.joinToString { "${it + 1}" }} saw no line"
                        detail.text = "They need at least ${LineCalibration.MIN_CONTRAST} counts between white and black. Is the robot on the line? Try again."
                        setButtons(button("Try again") { model.reset() })
                    }
                }
                is CalibrationStep.Writing -> {
                    headline.text = "Writing…"
                    detail.text = "Waiting for the robot to acknowledge cal_min and cal_max."
                    setButtons()
                }
                is CalibrationStep.Written -> {
                    chart.calibration = step.calibration
                    headline.text = "✓ Written: the robot uses it now"
                    detail.text = "Acknowledged by the robot. Save it to the robot's memory so it survives switching off?"
                    setButtons(button("Save on robot") { model.save() }, button("Done", ButtonStyle.OUTLINED) { model.reset() })
                }
                is CalibrationStep.Saved -> {
                    chart.calibration = step.calibration
                    headline.text = "✓ Saved in the robot's EEPROM"
                    detail.text = "The robot keeps this calibration after a reset."
                    setButtons(button("Done", ButtonStyle.OUTLINED) { model.reset() })
                }
                is CalibrationStep.Failed -> {
                    headline.text = "Calibration failed"
                    detail.text = step.message
                    setButtons(button("Start again") { model.reset() })
                }
            }
        }
    }
    robotScreen(session, scope, card("CALIBRATION", headline, gap(4), detail, gap(8), bar, chart, legend, gap(12), buttons))
}

/** Joystick: drag to drive, release to stop; or a step at a time with buttons (and TalkBack's actions). */
fun driveScreen(context: Context, session: RobotSession, scope: CoroutineScope): View = with(context) {
    val model = session.joystick
    val stick = JoystickCanvas(this).apply {
        onMove = { x, y -> model.move(x, y) }
        onRelease = { model.release() }
        steps = Step.entries.map { step -> step.label to { model.step(step) } }
    }
    val target = text("", 15f)
    val measured = text("", 15f, palette.TEXT_SOFT)
    val hint = text("", 14f, palette.TEXT_SOFT).apply { gravity = Gravity.CENTER }
    val maxLabel = text("", 15f)
    val slider = SeekBar(this).apply {
        max = ((JoystickModel.MAX_SPEED_MPS - JoystickModel.MIN_SPEED_MPS) * 100).toInt()
        progress = ((model.state.value.maxSpeedMps - JoystickModel.MIN_SPEED_MPS) * 100).toInt()
        layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, dp(TOUCH_TARGET_DP))
        contentDescription = "Top speed"
        setOnSeekBarChangeListener(object : SeekBar.OnSeekBarChangeListener {
            override fun onProgressChanged(seekBar: SeekBar, progress: Int, fromUser: Boolean) {
                if (fromUser) model.setMaxSpeed(JoystickModel.MIN_SPEED_MPS + progress / 100.0)
            }
            override fun onStartTrackingTouch(seekBar: SeekBar) {}
            override fun onStopTrackingTouch(seekBar: SeekBar) {}
        })
    }
    fun stepButton(step: Step) = button(step.label, ButtonStyle.OUTLINED) { model.step(step) }.apply { layoutParams = weight() }
    val steps = card(
        "STEP BY STEP",
        text("Each tap drives a short way and stops by itself.", 14f, palette.TEXT_SOFT), gap(8),
        horizontal(stepButton(Step.FORWARD), gap(8), stepButton(Step.BACK)), gap(8),
        horizontal(stepButton(Step.LEFT), gap(8), stepButton(Step.RIGHT)),
    )
    scope.launch {
        model.state.collect { s ->
            stick.knob = s.x to s.y
            stick.active = s.held
            target.text = "Wheels asked: left ${mps(s.leftMps)}, right ${mps(s.rightMps)}"
            maxLabel.text = "Top speed ${mps(s.maxSpeedMps)}"
            hint.text = s.stoppedBecause?.let { "Stopped: $it" } ?: if (s.held) "Driving — let go to stop" else "Hold and drag the knob to drive; let go and the robot stops."
            hint.setTextColor(if (s.stoppedBecause != null) palette.BAD else palette.TEXT_SOFT)
        }
    }
    scope.launch {
        combine(session.robot.motors.wheels, session.freshness) { w, f -> w to f }.collect { (w, f) ->
            measured.text = "Wheels measured: left ${mps(w.speedLeftMmps / 1000.0)}, right ${mps(w.speedRightMmps / 1000.0)}"
            measured.setTextColor(palette.live(f, palette.TEXT_SOFT))
        }
    }
    robotScreen(session, scope, card("JOYSTICK", hint, stick), steps, card("SPEED", maxLabel, slider, target, measured))
}

/** Line following: start and stop, speed, colour mode with the red and blue speeds. */
fun followScreen(context: Context, session: RobotSession, scope: CoroutineScope): View = with(context) {
    val model = session.lineFollow
    val status = text("", 20f, bold = true)
    val segment = text("", 14f)
    val speed = text("", 14f, palette.TEXT_SOFT)
    val start = button("Start") { model.start() }
    val stop = button("Stop", ButtonStyle.DANGER) { model.stop() }
    val (speedRow, showSpeed) = sliderRow("Speed on black", 0.5) { model.setSpeed(it) }
    val (redRow, showRed) = sliderRow("Red tape: slow down to", 0.5) { model.setRedSpeed(it) }
    val (blueRow, showBlue) = sliderRow("Blue tape: speed up to", 0.5) { model.setBlueSpeed(it) }
    fun radio(label: String) = RadioButton(this).apply {
        text = label
        id = View.generateViewId()
        textSize = 15f
        setTextColor(palette.TEXT)
        minHeight = dp(TOUCH_TARGET_DP)
    }
    val plain = radio("Plain: one speed")
    val segments = radio("Colour segments: red slows, blue speeds up")
    val modes = RadioGroup(this).apply {
        addView(plain); addView(segments)
        setOnCheckedChangeListener { _, checked -> model.setColourMode(if (checked == segments.id) ColourMode.SEGMENTS else ColourMode.PLAIN) }
    }
    scope.launch {
        combine(model.view, session.freshness) { v, f -> v to f }.collect { (v, f) ->
            status.text = when (v.status) {
                LineFollowStatus.FOLLOWING -> "● Following the line"
                LineFollowStatus.LOST -> "● Line lost: stopped"
                else -> "● Not following"
            }
            status.setTextColor(palette.live(f, when (v.status) { LineFollowStatus.FOLLOWING -> palette.GOOD; LineFollowStatus.LOST -> palette.BAD; else -> palette.TEXT_SOFT }))
            segment.text = "Under the robot: ${v.segment.name.lowercase()} tape"
            segment.setTextColor(palette.live(f, when (v.segment) { Colour.RED -> palette.RED_TAPE; Colour.BLUE -> palette.BLUE_TAPE; else -> palette.TEXT }))
            speed.text = "Speed now ${mps(v.speedMps)}"
            speed.setTextColor(palette.live(f, palette.TEXT_SOFT))
            val following = v.status == LineFollowStatus.FOLLOWING
            start.enabled(!following)
            stop.enabled(following)
            (if (v.colourMode == ColourMode.SEGMENTS) segments else plain).let { if (!it.isChecked) it.isChecked = true }
            redRow.enabled(v.colourMode == ColourMode.SEGMENTS)
            blueRow.enabled(v.colourMode == ColourMode.SEGMENTS)
            showSpeed(v.speed); showRed(v.redSpeed); showBlue(v.blueSpeed)
        }
    }
    robotScreen(
        session, scope,
        card("LINE FOLLOWING", status, segment, speed, gap(12), horizontal(start.apply { layoutParams = weight() }, gap(10), stop.apply { layoutParams = weight() })),
        card("SPEEDS (ROBOT SETTINGS)", speedRow),
        card("COLOUR MODE", modes, redRow, blueRow),
    )
}

/** Trajectory: the odometry path, live. */
fun pathScreen(context: Context, session: RobotSession, scope: CoroutineScope): View = with(context) {
    val model = session.trajectory
    val canvas = TrajectoryCanvas(this)
    val info = text("", 14f, palette.TEXT_SOFT)
    scope.launch {
        combine(model.view, session.freshness) { v, f -> v to f }.collect { (v, f) ->
            canvas.path = v
            canvas.stale = !f.live
            val heading = (Math.toDegrees(v.pose.headingRad) % 360 + 540) % 360 - 180 // -180..180
            info.text = "Travelled %.2f m · at x %.2f m, y %.2f m, heading %.0f°".format(v.lengthM, v.pose.xM, v.pose.yM, heading)
            info.setTextColor(palette.live(f, palette.TEXT))
        }
    }
    robotScreen(session, scope, card("TRAJECTORY (ODOMETRY)", canvas, gap(8), info, gap(8), horizontal(button("Clear path", ButtonStyle.OUTLINED) { model.clear() })))
}

/** What a robot screen shows while no robot is connected. */
fun noRobotScreen(context: Context, model: AppModel): View = with(context) {
    vertical(24,
        text("No robot connected", 20f, bold = true).apply { gravity = Gravity.CENTER },
        gap(8),
        text("Find a robot and connect it first.", 15f, palette.TEXT_SOFT).apply { gravity = Gravity.CENTER },
        gap(16),
        button("Find robots") { model.show(org.pocketbot.android.model.Screen.ROBOTS) }.apply {
            layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.WRAP_CONTENT, ViewGroup.LayoutParams.WRAP_CONTENT).apply { gravity = Gravity.CENTER_HORIZONTAL }
        },
    ).apply { gravity = Gravity.CENTER }
}
