package org.pocketbot.android

import android.graphics.Bitmap
import android.graphics.Color
import android.graphics.Insets
import android.view.View
import android.view.ViewGroup
import android.view.WindowInsets
import android.widget.CompoundButton
import android.widget.EditText
import android.widget.SeekBar
import android.widget.TextView
import org.junit.Test
import org.junit.runner.RunWith
import org.pocketbot.android.ui.JoystickCanvas
import org.pocketbot.android.ui.TOUCH_TARGET_DP
import org.robolectric.RuntimeEnvironment
import org.robolectric.annotation.Config
import org.robolectric.annotation.GraphicsMode
import kotlin.math.max
import kotlin.math.min
import kotlin.test.assertTrue
import kotlin.time.Duration.Companion.milliseconds

/**
 * Every screen as a person using TalkBack, large text or dark mode meets it, checked the way Android's Accessibility
 * Test Framework checks (its jar is not to be had here): touch targets of at least 48 dp, a spoken label on every
 * control, text contrast of at least 4.5:1 (3:1 for large text) against the pixels actually drawn behind it, and, at
 * the largest font size (200 %), no label cut, ellipsized or broken inside a word. The dark screens are photographed
 * into docs/images/android-*-dark.png (AppTest photographs the light ones in use).
 */
@RunWith(org.robolectric.RobolectricTestRunner::class)
@Config(sdk = [35], application = TestApp::class, qualifiers = "w360dp-h760dp-xhdpi")
@GraphicsMode(GraphicsMode.Mode.NATIVE)
class AccessibilityTest {
    @Test
    fun everyScreenPassesTheChecksInLightMode() = withApp { everyScreen(null) }

    @Test
    @Config(qualifiers = "w360dp-h760dp-night-xhdpi")
    fun everyScreenPassesTheChecksInDarkMode() = withApp { everyScreen("dark") }

    @Test
    fun everyLabelSurvivesTheLargestFont() {
        RuntimeEnvironment.setFontScale(2.0f)
        withApp {
            connectRobot()
            val problems = ArrayList<String>()
            for (screen in SCREENS) {
                click(screen)
                settle()
                problems += cutLabels().map { "$screen: $it" }
            }
            assertTrue(problems.isEmpty(), "labels cut at 200 % font size:\n" + problems.joinToString("\n"))
        }
    }

    /**
     * The app draws edge to edge (Android 15 enforces it for apps targeting 35; on 14 the app asks for it, else the
     * window would keep it below the bars): the top bar's colour reaches under the status bar, and its bars keep their
     * content clear of the status and navigation bars. (Robolectric shows no system bars: their insets are given to the
     * window here.)
     */
    @Test
    @Config(sdk = [34, 35])
    fun theBarsKeepClearOfTheSystemBars() = withApp {
        launch()
        val density = activity.resources.displayMetrics.density
        val status = (24 * density).toInt()
        val navigation = (48 * density).toInt()
        root.dispatchApplyWindowInsets(
            WindowInsets.Builder()
                .setInsets(WindowInsets.Type.statusBars(), Insets.of(0, status, 0, 0))
                .setInsets(WindowInsets.Type.navigationBars(), Insets.of(0, 0, 0, navigation))
                .build(),
        )
        root.requestLayout()
        run(50.milliseconds)
        val title = view("PocketBot")
        val tab = view("Path")
        val at = IntArray(2)
        title.getLocationInWindow(at)
        assertTrue(at[1] >= status, "the title starts below the status bar: ${at[1]} px < $status px")
        tab.getLocationInWindow(at)
        assertTrue(at[1] + tab.height <= root.height - navigation, "the tabs end above the navigation bar: ${at[1] + tab.height} > ${root.height - navigation}")
        val bar = title.parent.parent as View
        bar.getLocationInWindow(at)
        assertTrue(at[1] == 0, "the top bar's colour reaches under the status bar (edge to edge)")
    }

    /** Visits every screen (no robot, then connected), checking each and photographing it as android-NAME-[suffix]. */
    private suspend fun AppHarness.everyScreen(suffix: String?) {
        launch()
        val problems = ArrayList<String>()
        suspend fun check(name: String) {
            settle()
            val picture = screenshotOf(root)
            problems += findProblems(picture).map { "$name: $it" }
            if (suffix != null) screenshot("$name-$suffix")
        }
        click("Sensor")
        check("no-robot")
        click("Robots")
        click("Find robots")
        until("found") { model.found.value.isNotEmpty() }
        click("Connect")
        until("connected") { model.session.value != null }
        run(500.milliseconds)
        for (screen in SCREENS) {
            click(screen)
            check(screen.lowercase().let { if (it == "calibrate") "calibration" else it })
        }
        model.session.value!!.stopRobot()
        pressBack()
        check("back")
        dialog().dismiss()
        assertTrue(problems.isEmpty(), "accessibility problems:\n" + problems.joinToString("\n"))
    }

    /** Lets the main looper's clock move, so that the views are measured, laid out and drawn as a frame does it. */
    private suspend fun AppHarness.settle() {
        run(100.milliseconds)
        org.robolectric.Shadows.shadowOf(android.os.Looper.getMainLooper()).idleFor(java.time.Duration.ofMillis(100))
    }

    private fun AppHarness.screenshotOf(v: View): Bitmap {
        v.jumpDrawablesToCurrentState()
        return Bitmap.createBitmap(v.width, v.height, Bitmap.Config.ARGB_8888).also { v.draw(android.graphics.Canvas(it)) }
    }

    private fun AppHarness.findProblems(picture: Bitmap): List<String> {
        val density = activity.resources.displayMetrics.density
        val out = ArrayList<String>()
        for (v in shownViews(root)) {
            val name = describe(v)
            val control = v.isClickable || v.isLongClickable || v is JoystickCanvas || v is SeekBar || v is EditText || v is CompoundButton
            if (control && v.isEnabled) {
                if (v.width < TOUCH_TARGET_DP * density - 0.5f || v.height < TOUCH_TARGET_DP * density - 0.5f) {
                    out += "$name is ${(v.width / density).toInt()}x${(v.height / density).toInt()} dp, under 48x48"
                }
                val label = v.contentDescription ?: (v as? TextView)?.text?.takeIf { it.isNotBlank() } ?: (v as? EditText)?.hint
                if (label.isNullOrBlank()) out += "$name has nothing a screen reader can say"
            }
            if (v is TextView && v.text.isNotBlank() && v !is EditText && enabledAndOpaque(v)) {
                val ratio = contrast(v, picture)
                val large = v.textSize / density / activity.resources.configuration.fontScale >= 18 ||
                    (v.typeface?.isBold == true && v.textSize / density >= 14)
                val needed = if (large) 3.0 else 4.5
                if (ratio < needed) out += "$name: text contrast %.2f:1, under %.1f:1".format(ratio, needed)
            }
        }
        return out
    }

    /** Contrast of [v]'s text colour against the colour most of its area shows in [picture] (its background). */
    private fun contrast(v: TextView, picture: Bitmap): Double {
        val at = IntArray(2).also { v.getLocationInWindow(it) }
        val counts = HashMap<Int, Int>()
        for (y in max(0, at[1]) until min(picture.height, at[1] + v.height) step 2) {
            for (x in max(0, at[0]) until min(picture.width, at[0] + v.width) step 2) counts.merge(picture.getPixel(x, y), 1, Int::plus)
        }
        val background = counts.maxByOrNull { it.value }?.key ?: return 21.0
        val l1 = luminance(v.currentTextColor)
        val l2 = luminance(background)
        return (max(l1, l2) + 0.05) / (min(l1, l2) + 0.05)
    }

    private fun luminance(c: Int): Double {
        fun channel(v: Int) = (v / 255.0).let { if (it <= 0.03928) it / 12.92 else Math.pow((it + 0.055) / 1.055, 2.4) }
        return 0.2126 * channel(Color.red(c)) + 0.7152 * channel(Color.green(c)) + 0.0722 * channel(Color.blue(c))
    }

    /** Disabled or faded controls are exempt from the contrast rule (as the WCAG exempts inactive components). */
    private fun enabledAndOpaque(v: View): Boolean {
        var at: View? = v
        while (at != null) {
            if (!at.isEnabled || at.alpha < 1f) return false
            at = at.parent as? View
        }
        return true
    }

    /** Texts that do not show whole: ellipsized, wider or taller than their view, or a word broken across lines. */
    private fun AppHarness.cutLabels(): List<String> = shownViews(root).filterIsInstance<TextView>().filter { it.text.isNotBlank() && it !is EditText }.mapNotNull { v ->
        val layout = v.layout ?: return@mapNotNull null
        val text = v.text.toString()
        val room = v.width - v.totalPaddingLeft - v.totalPaddingRight
        when {
            (0 until layout.lineCount).any { layout.getEllipsisCount(it) > 0 } -> "\"$text\" is ellipsized"
            (0 until layout.lineCount).any { layout.getLineMax(it) > room + 1 } -> "\"$text\" is wider than its view"
            layout.height > v.height - v.totalPaddingTop - v.totalPaddingBottom + 1 -> "\"$text\" is taller than its view"
            (0 until layout.lineCount - 1).any { i ->
                val end = layout.getLineEnd(i)
                end in 1 until text.length && text[end - 1].isLetterOrDigit() && text[end].isLetterOrDigit()
            } -> "\"$text\" breaks inside a word"
            else -> null
        }
    }

    private fun shownViews(v: View): List<View> = buildList {
        if (!v.isShown) return@buildList
        add(v)
        if (v is ViewGroup) for (i in 0 until v.childCount) addAll(shownViews(v.getChildAt(i)))
    }

    private fun describe(v: View): String = "${v.javaClass.simpleName}(${(v as? TextView)?.text ?: v.contentDescription ?: ""})"

    private companion object {
        val SCREENS = listOf("Robots", "Sensor", "Calibrate", "Drive", "Follow", "Path")
    }
}
