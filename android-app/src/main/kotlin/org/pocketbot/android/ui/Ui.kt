package org.pocketbot.android.ui

import android.content.Context
import android.content.res.ColorStateList
import android.content.res.Configuration
import android.graphics.Color
import android.graphics.Typeface
import android.graphics.drawable.GradientDrawable
import android.graphics.drawable.RippleDrawable
import android.view.Gravity
import android.view.View
import android.view.ViewGroup
import android.widget.Button
import android.widget.LinearLayout
import android.widget.TextView
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.launch
import org.pocketbot.android.model.Freshness
import org.pocketbot.sdk.toDecimalString

/**
 * The app's colours, light and dark. Every text colour has at least 4.5:1 contrast on the backgrounds it is used on
 * (TEXT*, GOOD, WARN, BAD, the tape colours on CARD and BACKGROUND; ON_* on the fill they name; BAR_* on BAR).
 */
class Palette private constructor(
    val PRIMARY: Int, val ON_PRIMARY: Int, val PRIMARY_SOFT: Int, val ACCENT: Int,
    val BACKGROUND: Int, val CARD: Int, val OUTLINE: Int, val TEXT: Int, val TEXT_SOFT: Int,
    val GOOD: Int, val WARN: Int, val BAD: Int, val ON_BAD: Int, val RED_TAPE: Int, val BLUE_TAPE: Int,
    val BAR: Int, val BAR_TEXT: Int, val BAR_SOFT: Int, val BAR_GOOD: Int, val BAR_BAD: Int,
    val NOTICE_INFO: Int, val NOTICE_WARNING: Int, val NOTICE_ERROR: Int, val SPOT_BACK: Int,
    val night: Boolean,
) {
    companion object {
        val LIGHT = Palette(
            PRIMARY = Color.rgb(0x1E, 0x5A, 0xA8), ON_PRIMARY = Color.WHITE, PRIMARY_SOFT = Color.rgb(0xDC, 0xE8, 0xF7),
            ACCENT = Color.rgb(0xF2, 0x8C, 0x28),
            BACKGROUND = Color.rgb(0xF4, 0xF6, 0xF9), CARD = Color.WHITE, OUTLINE = Color.rgb(0xD5, 0xDA, 0xE1),
            TEXT = Color.rgb(0x1B, 0x1F, 0x24), TEXT_SOFT = Color.rgb(0x55, 0x60, 0x6E),
            GOOD = Color.rgb(0x1B, 0x7A, 0x43), WARN = Color.rgb(0x8A, 0x5A, 0x00), BAD = Color.rgb(0xC6, 0x28, 0x28), ON_BAD = Color.WHITE,
            RED_TAPE = Color.rgb(0xC6, 0x28, 0x28), BLUE_TAPE = Color.rgb(0x15, 0x65, 0xC0),
            BAR = Color.rgb(0x1E, 0x5A, 0xA8), BAR_TEXT = Color.WHITE, BAR_SOFT = Color.rgb(0xD6, 0xE2, 0xF2),
            BAR_GOOD = Color.rgb(0xB4, 0xF0, 0xC8), BAR_BAD = Color.rgb(0xFF, 0xCD, 0xC4),
            NOTICE_INFO = Color.rgb(0xE3, 0xF2, 0xE8), NOTICE_WARNING = Color.rgb(0xFF, 0xF3, 0xD6), NOTICE_ERROR = Color.rgb(0xFD, 0xE4, 0xE1),
            SPOT_BACK = Color.rgb(0xEE, 0xF1, 0xF5), night = false,
        )
        val DARK = Palette(
            PRIMARY = Color.rgb(0x8A, 0xB4, 0xF8), ON_PRIMARY = Color.rgb(0x0B, 0x1D, 0x36), PRIMARY_SOFT = Color.rgb(0x23, 0x34, 0x4D),
            ACCENT = Color.rgb(0xF2, 0x8C, 0x28),
            BACKGROUND = Color.rgb(0x12, 0x14, 0x17), CARD = Color.rgb(0x1E, 0x22, 0x27), OUTLINE = Color.rgb(0x3A, 0x41, 0x4A),
            TEXT = Color.rgb(0xE8, 0xEA, 0xED), TEXT_SOFT = Color.rgb(0xA9, 0xB3, 0xBF),
            GOOD = Color.rgb(0x7B, 0xD1, 0x9A), WARN = Color.rgb(0xF2, 0xC0, 0x66), BAD = Color.rgb(0xF2, 0x8B, 0x82), ON_BAD = Color.rgb(0x2B, 0x0B, 0x08),
            RED_TAPE = Color.rgb(0xF2, 0x8B, 0x82), BLUE_TAPE = Color.rgb(0x8A, 0xB4, 0xF8),
            BAR = Color.rgb(0x1B, 0x2A, 0x41), BAR_TEXT = Color.WHITE, BAR_SOFT = Color.rgb(0xC8, 0xD3, 0xE3),
            BAR_GOOD = Color.rgb(0xB4, 0xF0, 0xC8), BAR_BAD = Color.rgb(0xFF, 0xB4, 0xAA),
            NOTICE_INFO = Color.rgb(0x1E, 0x3A, 0x2A), NOTICE_WARNING = Color.rgb(0x3D, 0x32, 0x18), NOTICE_ERROR = Color.rgb(0x4A, 0x1F, 0x1C),
            SPOT_BACK = Color.rgb(0x2A, 0x2F, 0x36), night = true,
        )
    }
}

/** The palette of this context's theme: dark when the phone is in dark mode. */
val Context.palette: Palette
    get() = if (resources.configuration.uiMode and Configuration.UI_MODE_NIGHT_MASK == Configuration.UI_MODE_NIGHT_YES) Palette.DARK else Palette.LIGHT

fun Context.dp(value: Number): Int = (value.toFloat() * resources.displayMetrics.density + 0.5f).toInt()

fun Context.dpf(value: Number): Float = value.toFloat() * resources.displayMetrics.density

/** The smallest side of anything a finger must hit (Android's accessibility guideline). */
const val TOUCH_TARGET_DP = 48

fun rounded(context: Context, color: Int, radiusDp: Number, strokeColor: Int? = null): GradientDrawable = GradientDrawable().apply {
    setColor(color)
    cornerRadius = context.dpf(radiusDp)
    if (strokeColor != null) setStroke(context.dp(1), strokeColor)
}

fun Context.text(text: CharSequence = "", sizeSp: Float = 15f, color: Int = palette.TEXT, bold: Boolean = false): TextView =
    TextView(this).apply {
        this.text = text
        textSize = sizeSp
        setTextColor(color)
        if (bold) typeface = Typeface.create(Typeface.DEFAULT, Typeface.BOLD)
    }

fun Context.vertical(paddingDp: Int = 0, vararg children: View): LinearLayout = LinearLayout(this).apply {
    orientation = LinearLayout.VERTICAL
    setPadding(dp(paddingDp), dp(paddingDp), dp(paddingDp), dp(paddingDp))
    children.forEach { addView(it) }
}

fun Context.horizontal(vararg children: View): LinearLayout = LinearLayout(this).apply {
    orientation = LinearLayout.HORIZONTAL
    gravity = Gravity.CENTER_VERTICAL
    children.forEach { addView(it) }
}

/** A card with a title (a heading for screen readers), holding [children] one below the other. */
fun Context.card(title: String?, vararg children: View): LinearLayout = vertical(16).apply {
    background = rounded(context, palette.CARD, 14, palette.OUTLINE)
    elevation = dpf(1)
    if (title != null) addView(text(title, 13f, palette.TEXT_SOFT, bold = true).apply {
        letterSpacing = 0.06f
        setPadding(0, 0, 0, dp(8))
        heading()
    })
    children.forEach { addView(it) }
    layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.WRAP_CONTENT).apply {
        setMargins(dp(12), dp(6), dp(12), dp(6))
    }
}

enum class ButtonStyle { FILLED, OUTLINED, DANGER }

/** A rounded button in the app's colours, at least [TOUCH_TARGET_DP] high. */
fun Context.button(label: String, style: ButtonStyle = ButtonStyle.FILLED, onClick: () -> Unit): Button = Button(this).apply {
    text = label
    isAllCaps = false
    textSize = 15f
    typeface = Typeface.create(Typeface.DEFAULT, Typeface.BOLD)
    stateListAnimator = null
    minHeight = dp(TOUCH_TARGET_DP)
    minimumHeight = dp(TOUCH_TARGET_DP)
    minWidth = dp(TOUCH_TARGET_DP)
    minimumWidth = dp(TOUCH_TARGET_DP)
    setPadding(dp(18), dp(6), dp(18), dp(6))
    val p = palette
    val (fill, fg, stroke) = when (style) {
        ButtonStyle.FILLED -> Triple(p.PRIMARY, p.ON_PRIMARY, null)
        ButtonStyle.OUTLINED -> Triple(p.CARD, p.PRIMARY, p.PRIMARY)
        ButtonStyle.DANGER -> Triple(p.BAD, p.ON_BAD, null)
    }
    setTextColor(fg)
    background = RippleDrawable(ColorStateList.valueOf(Color.argb(60, 0, 0, 0)), rounded(context, fill, 24, stroke), null)
    setOnClickListener { onClick() }
}

/** Marks [this] as a heading for screen readers (Android 9 on; before, TalkBack reads it as text). */
fun View.heading() {
    if (android.os.Build.VERSION.SDK_INT >= android.os.Build.VERSION_CODES.P) isAccessibilityHeading = true
}

/** What a screen reader says of [this]'s state (Android 11 on; before, the content description must tell it). */
fun View.state(description: String) {
    if (android.os.Build.VERSION.SDK_INT >= android.os.Build.VERSION_CODES.R) stateDescription = description
}

/** Enables or disables [this]; a disabled control is faded (and, as Android says, not operable). */
fun View.enabled(on: Boolean) {
    isEnabled = on
    alpha = if (on) 1f else 0.4f
}

fun weight(w: Float = 1f): LinearLayout.LayoutParams = LinearLayout.LayoutParams(0, ViewGroup.LayoutParams.WRAP_CONTENT, w)

fun Context.gap(dp: Int): View = View(this).apply { layoutParams = LinearLayout.LayoutParams(dp(dp), dp(dp)) }

fun mps(v: Double): String = "%.2f m/s".format(v)

/**
 * A speed setting in m/s as people read it: the shortest decimal that reads back to the same 32-bit float the robot
 * holds, never in scientific notation (`0.15`, not `0.15000000596` or `1.5E-1`).
 */
fun settingMps(v: Double): String = "${v.toFloat().toDecimalString()} m/s"

/** [colour] while the values are live, the soft grey of old values otherwise. */
fun Palette.live(f: Freshness, colour: Int): Int = if (f.live) colour else TEXT_SOFT

/** A banner that appears while [freshness] is not live: how old the values below it are, and why. */
fun Context.staleBanner(scope: CoroutineScope, freshness: StateFlow<Freshness>): TextView {
    val banner = text("", 14f, palette.TEXT).apply {
        background = rounded(context, palette.NOTICE_WARNING, 10)
        setPadding(dp(12), dp(8), dp(12), dp(8))
        accessibilityLiveRegion = View.ACCESSIBILITY_LIVE_REGION_POLITE
        layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.WRAP_CONTENT).apply {
            setMargins(dp(12), dp(6), dp(12), dp(0))
        }
    }
    scope.launch {
        freshness.collect { f ->
            banner.visibility = if (f.live) View.GONE else View.VISIBLE
            if (!f.live) banner.text = "Not live: last heard ${f.age} ago (${f.why}). Grey values are the last known."
        }
    }
    return banner
}
