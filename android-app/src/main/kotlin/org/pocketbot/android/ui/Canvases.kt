package org.pocketbot.android.ui

import android.content.Context
import android.graphics.Canvas
import android.graphics.Color
import android.graphics.Paint
import android.graphics.Path
import android.graphics.RectF
import android.os.Bundle
import android.view.MotionEvent
import android.view.View
import android.view.accessibility.AccessibilityNodeInfo
import org.pocketbot.android.model.LineSensorReading
import org.pocketbot.android.model.TrajectoryView
import org.pocketbot.sdk.LineCalibration
import kotlin.math.cos
import kotlin.math.hypot
import kotlin.math.max
import kotlin.math.min
import kotlin.math.sin

private fun paint(color: Int, style: Paint.Style = Paint.Style.FILL, strokeWidth: Float = 0f) =
    Paint(Paint.ANTI_ALIAS_FLAG).apply { this.color = color; this.style = style; this.strokeWidth = strokeWidth }

/**
 * The eight spots of the line sensor from above, left to right: each a column whose fill is its darkness (the line
 * is black), with the threshold marked; under them the line position on its -1000..1000 scale.
 */
class LineSensorCanvas(context: Context) : View(context) {
    var reading: LineSensorReading? = null
        set(value) {
            field = value
            contentDescription = value?.let(::describe)
            invalidate()
        }

    /** The reading is old (the link is down): drawn faded. */
    var stale: Boolean = false
        set(value) { field = value; alpha = if (value) 0.45f else 1f }

    private val p = context.palette
    private val spotBack = paint(p.SPOT_BACK)
    private val spotFill = paint(p.TEXT)
    private val seenFill = paint(p.ACCENT)
    private val outline = paint(p.OUTLINE, Paint.Style.STROKE, context.dpf(1))
    private val thresholdLine = paint(p.BAD, Paint.Style.STROKE, context.dpf(1.5f))
    private val label = paint(p.TEXT_SOFT).apply { textSize = context.dpf(11); textAlign = Paint.Align.CENTER }
    private val scale = paint(p.OUTLINE, Paint.Style.STROKE, context.dpf(2))
    private val marker = paint(p.PRIMARY)

    /** What a screen reader says: the line, then each spot's darkness. */
    private fun describe(r: LineSensorReading): String =
        (if (r.seen) "Line at ${r.position} per mille, " else "No line, ") +
            "darkness of spots 1 to 8: " + r.darkness.joinToString { "${it / 10} percent" }

    override fun onMeasure(widthMeasureSpec: Int, heightMeasureSpec: Int) {
        val w = MeasureSpec.getSize(widthMeasureSpec)
        setMeasuredDimension(w, context.dp(250))
    }

    override fun onDraw(canvas: Canvas) {
        val r = reading ?: return
        val pad = context.dpf(8)
        val gap = context.dpf(8)
        val colW = (width - 2 * pad - 7 * gap) / 8
        val top = context.dpf(8)
        val colH = context.dpf(150)
        for (i in 0 until 8) {
            val left = pad + i * (colW + gap)
            val rect = RectF(left, top, left + colW, top + colH)
            canvas.drawRoundRect(rect, context.dpf(8), context.dpf(8), spotBack)
            val d = r.darkness[i] / 1000f
            val fill = RectF(left, top + colH * (1 - d), left + colW, top + colH)
            canvas.save()
            canvas.clipRect(fill)
            canvas.drawRoundRect(rect, context.dpf(8), context.dpf(8), if (r.darkness[i] > r.threshold) seenFill else spotFill)
            canvas.restore()
            canvas.drawRoundRect(rect, context.dpf(8), context.dpf(8), outline)
            val ty = top + colH * (1 - r.threshold / 1000f)
            canvas.drawLine(left, ty, left + colW, ty, thresholdLine)
            canvas.drawText("${r.raw[i]}", left + colW / 2, top + colH + context.dpf(16), label)
            canvas.drawText("${r.darkness[i] / 10}%", left + colW / 2, top + colH + context.dpf(30), label)
        }
        // The line position scale: -1000 at the leftmost spot's centre, 1000 at the rightmost's.
        val y = top + colH + context.dpf(58)
        val x0 = pad + colW / 2
        val x1 = width - pad - colW / 2
        canvas.drawLine(x0, y, x1, y, scale)
        canvas.drawLine((x0 + x1) / 2, y - context.dpf(6), (x0 + x1) / 2, y + context.dpf(6), scale)
        if (r.seen) {
            val x = x0 + (x1 - x0) * (r.position + 1000) / 2000f
            val tri = Path().apply {
                moveTo(x, y - context.dpf(4)); lineTo(x - context.dpf(9), y - context.dpf(18)); lineTo(x + context.dpf(9), y - context.dpf(18)); close()
            }
            canvas.drawPath(tri, marker)
            canvas.drawCircle(x, y, context.dpf(6), marker)
        }
        canvas.drawText("left", x0, y + context.dpf(20), label)
        canvas.drawText("right", x1, y + context.dpf(20), label)
    }
}

/** Per spot, the white and black readings of a calibration as a range on a 0..4095 scale, weak spots in red. */
class CalibrationCanvas(context: Context) : View(context) {
    var calibration: LineCalibration? = null
        set(value) { field = value; invalidate() }

    /** Readings of a sweep still running: drawn the same way, without judging them. */
    var partial: Pair<List<Int>, List<Int>>? = null
        set(value) { field = value; invalidate() }

    private val p = context.palette
    private val track = paint(p.SPOT_BACK)
    private val range = paint(p.PRIMARY)
    private val weak = paint(p.BAD)
    private val label = paint(p.TEXT_SOFT).apply { textSize = context.dpf(11); textAlign = Paint.Align.CENTER }
    private val white = paint(Color.WHITE)
    private val whiteEdge = paint(p.TEXT_SOFT, Paint.Style.STROKE, context.dpf(1))
    private val black = paint(if (p.night) Color.BLACK else p.TEXT)

    override fun invalidate() {
        val (lows, highs) = calibration?.let { it.white to it.black } ?: partial ?: (null to null)
        contentDescription = if (lows == null || highs == null) null else
            "White and black readings per spot: " + lows.indices.joinToString { "spot ${it + 1}: ${lows[it]} and ${highs.getOrNull(it)}" }
        super.invalidate()
    }

    override fun onMeasure(widthMeasureSpec: Int, heightMeasureSpec: Int) {
        setMeasuredDimension(MeasureSpec.getSize(widthMeasureSpec), context.dp(200))
    }

    override fun onDraw(canvas: Canvas) {
        val (lows, highs, weakSpots) = calibration?.let { Triple(it.white, it.black, it.weakSpots) }
            ?: partial?.let { Triple(it.first, it.second, emptyList<Int>()) } ?: return
        if (lows.size < 8 || highs.size < 8) return
        val pad = context.dpf(8)
        val gap = context.dpf(8)
        val colW = (width - 2 * pad - 7 * gap) / 8
        val top = context.dpf(10)
        val h = context.dpf(140)
        fun yOf(adc: Int) = top + h * (1 - adc.coerceIn(0, LineCalibration.MAX_ADC) / LineCalibration.MAX_ADC.toFloat())
        for (i in 0 until 8) {
            val left = pad + i * (colW + gap)
            val cx = left + colW / 2
            canvas.drawRoundRect(RectF(cx - context.dpf(4), top, cx + context.dpf(4), top + h), context.dpf(4), context.dpf(4), track)
            val yWhite = yOf(lows[i])
            val yBlack = yOf(highs[i])
            if (highs[i] >= lows[i]) {
                canvas.drawRoundRect(RectF(cx - context.dpf(4), yBlack, cx + context.dpf(4), yWhite), context.dpf(4), context.dpf(4), if (i in weakSpots) weak else range)
            }
            canvas.drawCircle(cx, yWhite, context.dpf(6), white)
            canvas.drawCircle(cx, yWhite, context.dpf(6), whiteEdge)
            canvas.drawCircle(cx, yBlack, context.dpf(6), black)
            canvas.drawText("${lows[i]}", cx, top + h + context.dpf(18), label)
            canvas.drawText("${highs[i]}", cx, top + h + context.dpf(32), label)
            canvas.drawText("${i + 1}", cx, top + h + context.dpf(48), label.apply { isFakeBoldText = true })
            label.isFakeBoldText = false
        }
    }
}

/**
 * A touch joystick: a round pad and a knob the finger drags. Only a touch that lands on the pad drives: [onMove] gets
 * the knob's deflection (x right, y forward, each -1..1) while that finger is down, [onRelease] when it lifts or the
 * gesture is cancelled; a touch beside the pad is left to the screen (it scrolls). For screen readers it is one
 * control with the [steps] as its actions (a finger must hold the knob, which TalkBack users cannot).
 */
class JoystickCanvas(context: Context) : View(context) {
    var onMove: (Double, Double) -> Unit = { _, _ -> }
    var onRelease: () -> Unit = {}

    /** The knob as the model has it (it springs back to the centre on release). */
    var knob: Pair<Double, Double> = 0.0 to 0.0
        set(value) { field = value; invalidate() }
    var active: Boolean = false
        set(value) {
            field = value
            state(if (value) "driving" else "stopped")
            invalidate()
        }

    /** The drives a screen reader offers as actions of this control: a label and what it does. */
    var steps: List<Pair<String, () -> Unit>> = emptyList()
    private var finger = -1

    private val p = context.palette
    private val pad = paint(p.PRIMARY_SOFT)
    private val ring = paint(p.PRIMARY, Paint.Style.STROKE, context.dpf(2))
    private val cross = paint(Color.argb(90, Color.red(p.PRIMARY), Color.green(p.PRIMARY), Color.blue(p.PRIMARY)), Paint.Style.STROKE, context.dpf(1))
    private val knobPaint = paint(p.PRIMARY)
    private val knobActive = paint(p.ACCENT)
    private val arrow = paint(Color.argb(140, Color.red(p.PRIMARY), Color.green(p.PRIMARY), Color.blue(p.PRIMARY)))

    private val radius: Float get() = min(width, height) / 2f - context.dpf(36)

    init {
        contentDescription = "Joystick"
        state("stopped")
    }

    override fun onMeasure(widthMeasureSpec: Int, heightMeasureSpec: Int) {
        val w = MeasureSpec.getSize(widthMeasureSpec)
        setMeasuredDimension(w, min(w, context.dp(320)))
    }

    override fun onInitializeAccessibilityNodeInfo(info: AccessibilityNodeInfo) {
        super.onInitializeAccessibilityNodeInfo(info)
        steps.forEachIndexed { i, (label, _) -> info.addAction(AccessibilityNodeInfo.AccessibilityAction(STEP_ACTION + i, label)) }
    }

    override fun performAccessibilityAction(action: Int, arguments: Bundle?): Boolean {
        steps.getOrNull(action - STEP_ACTION)?.let { (_, run) -> run(); return true }
        return super.performAccessibilityAction(action, arguments)
    }

    override fun onDraw(canvas: Canvas) {
        val cx = width / 2f
        val cy = height / 2f
        val r = radius
        canvas.drawCircle(cx, cy, r, pad)
        canvas.drawCircle(cx, cy, r, ring)
        canvas.drawLine(cx - r, cy, cx + r, cy, cross)
        canvas.drawLine(cx, cy - r, cx, cy + r, cross)
        for (k in 0 until 4) {
            val a = Math.PI / 2 * k
            val tip = r - context.dpf(10)
            val path = Path().apply {
                moveTo(cx + (tip * cos(a)).toFloat(), cy - (tip * sin(a)).toFloat())
                lineTo(cx + ((tip - context.dpf(14)) * cos(a) - context.dpf(10) * sin(a)).toFloat(), cy - ((tip - context.dpf(14)) * sin(a) + context.dpf(10) * cos(a)).toFloat())
                lineTo(cx + ((tip - context.dpf(14)) * cos(a) + context.dpf(10) * sin(a)).toFloat(), cy - ((tip - context.dpf(14)) * sin(a) - context.dpf(10) * cos(a)).toFloat())
                close()
            }
            canvas.drawPath(path, arrow)
        }
        val kx = cx + (knob.first * r).toFloat()
        val ky = cy - (knob.second * r).toFloat()
        canvas.drawCircle(kx, ky, context.dpf(34), if (active) knobActive else knobPaint)
    }

    override fun onTouchEvent(event: MotionEvent): Boolean {
        val r = radius
        when (event.actionMasked) {
            MotionEvent.ACTION_DOWN -> {
                // Only the pad (and the knob standing on its rim) drives; a touch beside it belongs to the screen.
                if (hypot(event.x - width / 2f, event.y - height / 2f) > r + context.dpf(20)) return false
                finger = event.getPointerId(0)
                parent?.requestDisallowInterceptTouchEvent(true)
                moveTo(event.x, event.y, r)
            }
            MotionEvent.ACTION_MOVE -> {
                val at = event.findPointerIndex(finger)
                if (at >= 0) moveTo(event.getX(at), event.getY(at), r)
            }
            MotionEvent.ACTION_POINTER_UP -> if (event.getPointerId(event.actionIndex) == finger) release()
            MotionEvent.ACTION_UP, MotionEvent.ACTION_CANCEL -> release()
            else -> return super.onTouchEvent(event)
        }
        return true
    }

    private fun moveTo(x: Float, y: Float, r: Float) {
        val dx = ((x - width / 2f) / r).toDouble()
        val dy = (-(y - height / 2f) / r).toDouble()
        val len = max(1.0, hypot(dx, dy))
        onMove(dx / len, dy / len)
    }

    private fun release() {
        finger = -1
        onRelease()
    }

    private companion object {
        /** Ids of the step actions (custom actions need ids of their own, apart from Android's standard ones). */
        const val STEP_ACTION = 0x7F0B0100
    }
}

/**
 * The odometry path, fitted into the view with a margin and a 10 cm grid, the robot as a triangle at its pose.
 * x points right and y up, as on the floor seen from above.
 */
class TrajectoryCanvas(context: Context) : View(context) {
    var path: TrajectoryView? = null
        set(value) {
            field = value
            contentDescription = value?.let { "Path of %.2f metres, the robot at x %.2f, y %.2f metres".format(it.lengthM, it.pose.xM, it.pose.yM) }
            invalidate()
        }

    /** The path is old (the link is down): drawn faded. */
    var stale: Boolean = false
        set(value) { field = value; alpha = if (value) 0.45f else 1f }

    private val p = context.palette
    private val grid = paint(p.OUTLINE, Paint.Style.STROKE, context.dpf(1))
    private val line = paint(p.PRIMARY, Paint.Style.STROKE, context.dpf(3)).apply { strokeJoin = Paint.Join.ROUND; strokeCap = Paint.Cap.ROUND }
    private val robot = paint(p.ACCENT)
    private val start = paint(p.GOOD)
    private val label = paint(p.TEXT_SOFT).apply { textSize = context.dpf(11) }
    private val back = paint(p.CARD)

    override fun onMeasure(widthMeasureSpec: Int, heightMeasureSpec: Int) {
        val w = MeasureSpec.getSize(widthMeasureSpec)
        setMeasuredDimension(w, w)
    }

    override fun onDraw(canvas: Canvas) {
        canvas.drawRoundRect(RectF(0f, 0f, width.toFloat(), height.toFloat()), context.dpf(14), context.dpf(14), back)
        val v = path ?: return
        val xs = v.points.map { it.pose.xM } + v.pose.xM
        val ys = v.points.map { it.pose.yM } + v.pose.yM
        // At least 20 cm across, so a robot standing still is not blown up to fill the view.
        val cxM = (xs.min() + xs.max()) / 2
        val cyM = (ys.min() + ys.max()) / 2
        val spanM = max(0.2, max(xs.max() - xs.min(), ys.max() - ys.min()) * 1.15)
        val scale = (min(width, height) - context.dpf(24)) / spanM
        fun px(x: Double) = (width / 2f + (x - cxM) * scale).toFloat()
        fun py(y: Double) = (height / 2f - (y - cyM) * scale).toFloat()
        val step = 0.1
        var gx = Math.floor((cxM - spanM) / step) * step
        while (gx <= cxM + spanM) { canvas.drawLine(px(gx), 0f, px(gx), height.toFloat(), grid); gx += step }
        var gy = Math.floor((cyM - spanM) / step) * step
        while (gy <= cyM + spanM) { canvas.drawLine(0f, py(gy), width.toFloat(), py(gy), grid); gy += step }
        canvas.drawText("grid 10 cm", context.dpf(10), height - context.dpf(10), label)
        if (v.points.isNotEmpty()) {
            val p = Path()
            v.points.forEachIndexed { i, point -> if (i == 0) p.moveTo(px(point.pose.xM), py(point.pose.yM)) else p.lineTo(px(point.pose.xM), py(point.pose.yM)) }
            p.lineTo(px(v.pose.xM), py(v.pose.yM))
            canvas.drawPath(p, line)
            canvas.drawCircle(px(v.points.first().pose.xM), py(v.points.first().pose.yM), context.dpf(5), start)
        }
        val h = v.pose.headingRad
        val x = px(v.pose.xM)
        val y = py(v.pose.yM)
        val s = context.dpf(14)
        val tri = Path().apply {
            moveTo(x + (s * cos(h)).toFloat(), y - (s * sin(h)).toFloat())
            lineTo(x + (s * 0.7 * cos(h + 2.5)).toFloat(), y - (s * 0.7 * sin(h + 2.5)).toFloat())
            lineTo(x + (s * 0.7 * cos(h - 2.5)).toFloat(), y - (s * 0.7 * sin(h - 2.5)).toFloat())
            close()
        }
        canvas.drawPath(tri, robot)
    }
}

