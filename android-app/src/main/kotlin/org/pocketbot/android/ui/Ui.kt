package org.pocketbot.android.ui

import android.content.Context
import android.content.res.ColorStateList
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

/** The app's colours. */
object Palette {
    val PRIMARY = Color.rgb(0x1E, 0x5A, 0xA8)
    val PRIMARY_DARK = Color.rgb(0x17, 0x46, 0x7F)
    val PRIMARY_SOFT = Color.rgb(0xDC, 0xE8, 0xF7)
    val ACCENT = Color.rgb(0xF2, 0x8C, 0x28)
    val BACKGROUND = Color.rgb(0xF4, 0xF6, 0xF9)
    val CARD = Color.WHITE
    val OUTLINE = Color.rgb(0xE1, 0xE5, 0xEB)
    val TEXT = Color.rgb(0x1B, 0x1F, 0x24)
    val TEXT_SOFT = Color.rgb(0x5F, 0x6B, 0x7A)
    val GOOD = Color.rgb(0x2E, 0x9D, 0x5B)
    val WARN = Color.rgb(0xE0, 0x9A, 0x00)
    val BAD = Color.rgb(0xD6, 0x45, 0x45)
    val RED_TAPE = Color.rgb(0xE5, 0x39, 0x35)
    val BLUE_TAPE = Color.rgb(0x1E, 0x88, 0xE5)
}

fun Context.dp(value: Number): Int = (value.toFloat() * resources.displayMetrics.density + 0.5f).toInt()

fun Context.dpf(value: Number): Float = value.toFloat() * resources.displayMetrics.density

fun rounded(context: Context, color: Int, radiusDp: Number, strokeColor: Int? = null): GradientDrawable = GradientDrawable().apply {
    setColor(color)
    cornerRadius = context.dpf(radiusDp)
    if (strokeColor != null) setStroke(context.dp(1), strokeColor)
}

fun Context.text(text: CharSequence = "", sizeSp: Float = 15f, color: Int = Palette.TEXT, bold: Boolean = false): TextView =
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

/** A white card with a title, holding [children] one below the other. */
fun Context.card(title: String?, vararg children: View): LinearLayout = vertical(16).apply {
    background = rounded(context, Palette.CARD, 14, Palette.OUTLINE)
    elevation = dpf(1)
    if (title != null) addView(text(title, 13f, Palette.TEXT_SOFT, bold = true).apply { letterSpacing = 0.06f; setPadding(0, 0, 0, dp(8)) })
    children.forEach { addView(it) }
    layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.WRAP_CONTENT).apply {
        setMargins(dp(12), dp(6), dp(12), dp(6))
    }
}

enum class ButtonStyle { FILLED, OUTLINED, DANGER }

/** A rounded button in the app's colours. */
fun Context.button(label: String, style: ButtonStyle = ButtonStyle.FILLED, onClick: () -> Unit): Button = Button(this).apply {
    text = label
    isAllCaps = false
    textSize = 15f
    typeface = Typeface.create(Typeface.DEFAULT, Typeface.BOLD)
    stateListAnimator = null
    minHeight = dp(44)
    minimumHeight = dp(44)
    setPadding(dp(18), 0, dp(18), 0)
    val (fill, fg, stroke) = when (style) {
        ButtonStyle.FILLED -> Triple(Palette.PRIMARY, Color.WHITE, null)
        ButtonStyle.OUTLINED -> Triple(Color.WHITE, Palette.PRIMARY, Palette.PRIMARY)
        ButtonStyle.DANGER -> Triple(Palette.BAD, Color.WHITE, null)
    }
    setTextColor(fg)
    background = RippleDrawable(ColorStateList.valueOf(Color.argb(60, 0, 0, 0)), rounded(context, fill, 22, stroke), null)
    setOnClickListener { onClick() }
}

fun View.enabled(on: Boolean) {
    isEnabled = on
    alpha = if (on) 1f else 0.4f
}

fun weight(w: Float = 1f, heightDp: Int? = null, context: Context? = null): LinearLayout.LayoutParams =
    LinearLayout.LayoutParams(0, if (heightDp != null && context != null) context.dp(heightDp) else ViewGroup.LayoutParams.WRAP_CONTENT, w)

fun Context.gap(dp: Int): View = View(this).apply { layoutParams = LinearLayout.LayoutParams(dp(dp), dp(dp)) }

fun mps(v: Double): String = "%.2f m/s".format(v)
