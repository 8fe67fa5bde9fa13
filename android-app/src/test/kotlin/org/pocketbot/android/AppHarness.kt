package org.pocketbot.android

import android.Manifest
import android.app.Application
import android.graphics.Bitmap
import android.graphics.Canvas
import android.os.Build
import android.os.Looper
import android.view.InputDevice
import android.view.KeyCharacterMap
import android.view.KeyEvent
import android.view.MotionEvent
import android.view.View
import android.view.ViewGroup
import android.widget.CompoundButton
import android.widget.TextView
import kotlinx.coroutines.CoroutineExceptionHandler
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.delay
import kotlinx.coroutines.plus
import kotlinx.coroutines.runBlocking
import kotlinx.coroutines.withTimeout
import org.pocketbot.android.bluetooth.BluetoothAccess
import org.pocketbot.android.model.AppModel
import org.pocketbot.emulator.Emulator
import org.pocketbot.emulator.runSimulated
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.EmulatorDiscoverer
import org.robolectric.Robolectric
import org.robolectric.RuntimeEnvironment
import org.robolectric.Shadows.shadowOf
import java.io.File
import kotlin.time.Duration
import kotlin.time.Duration.Companion.milliseconds
import kotlin.time.Duration.Companion.seconds

/** The Application under test: the model is the one a test builds (on the emulator's simulated time). */
class TestApp : Application(), ModelOwner {
    override lateinit var model: AppModel
    override lateinit var bluetoothAccess: BluetoothAccess
    override lateinit var connectionService: ConnectionService.Keeper
}

/**
 * The app as a person uses it, against an emulator running the real firmware. [activity] is the real [MainActivity].
 *
 * On simulated time (the default): the emulator in process, the model, the robots' SDK work and the views' collectors
 * all run on the test's (Robolectric's main) thread, in step with the emulator. In [realTime]: the emulator runs on its
 * own thread and robots are reached over real sockets (Bluetooth bridged to TCP), the SDK works on its own threads,
 * and waiting lets real time pass with the main looper running along, as on a phone.
 */
class AppHarness(
    val emulator: Emulator,
    val scope: CoroutineScope,
    sources: Map<String, Discoverer> = mapOf("emulator" to emulator.discoverer()),
    private val realTime: Boolean = false,
) {
    val app: TestApp = RuntimeEnvironment.getApplication() as TestApp

    /** What would have ended the app on a phone: an exception no coroutine of the app caught. */
    val crashed: MutableList<Throwable> = java.util.Collections.synchronizedList(ArrayList())
    private val crashes = CoroutineExceptionHandler { _, e -> crashed += e }
    val model: AppModel
    lateinit var activity: MainActivity
        private set
    lateinit var controller: org.robolectric.android.controller.ActivityController<MainActivity>
        private set

    init {
        shadowOf(app).grantPermissions(Manifest.permission.BLUETOOTH_SCAN, Manifest.permission.BLUETOOTH_CONNECT)
        if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.TIRAMISU) {
            app.applicationInfo.setEnableOnBackInvokedCallback(manifestOptsInToBackCallback())
        }
        app.bluetoothAccess = BluetoothAccess(app)
        model = AppModel(scope + crashes, app.bluetoothAccess, sources) { host, port -> EmulatorDiscoverer(host, port) }
        app.model = model
        app.connectionService = ConnectionService.Keeper(app, model) // as PocketBotApp does
    }

    /**
     * Whether the app's manifest opts in to OnBackInvokedCallback (`android:enableOnBackInvokedCallback`), as Android's
     * package manager reads it on 13 and later. Robolectric's manifest parser (Android's older PackageParser) skips
     * that attribute, so the harness reads it from the manifest the app is built from.
     */
    private fun manifestOptsInToBackCallback(): Boolean {
        val config = java.util.Properties()
        AppHarness::class.java.getResourceAsStream("/com/android/tools/test_config.properties")!!.use { config.load(it) }
        val manifest = javax.xml.parsers.DocumentBuilderFactory.newInstance().apply { isNamespaceAware = true }
            .newDocumentBuilder().parse(File(config.getProperty("android_merged_manifest")))
        val application = manifest.getElementsByTagName("application").item(0) as org.w3c.dom.Element
        return application.getAttributeNS("http://schemas.android.com/apk/res/android", "enableOnBackInvokedCallback") == "true"
    }

    suspend fun launch(): MainActivity {
        // The window manager gives the resumed Activity's window the input focus (keys such as Back go to it).
        controller = Robolectric.buildActivity(MainActivity::class.java).setup().windowFocusChanged(true)
        activity = controller.get()
        run(20.milliseconds)
        return activity
    }

    /** The phone turned: the Activity is destroyed and made again, the process stays. */
    suspend fun rotate() {
        controller.recreate().windowFocusChanged(true)
        activity = controller.get()
        run(20.milliseconds)
    }

    /**
     * The user presses Back: the key goes into the window's input queue (its ViewRootImpl) as Android's input dispatcher
     * sends it, and the platform's own code decides where it goes. Android 13 and later (the app opts in to
     * OnBackInvokedCallback) take it out of the queue before any view sees it and hand it to the window's top callback:
     * the app's while it registered one, else the system's (on Android 12 and later, the app moves to the background).
     * Before 13 it goes through the views to the Activity: onKeyDown, onKeyUp, onBackPressed.
     */
    suspend fun pressBack() {
        val window = root.viewRootImpl ?: throw AssertionError("the Activity's window is not on screen")
        val down = android.os.SystemClock.uptimeMillis()
        for (action in listOf(KeyEvent.ACTION_DOWN, KeyEvent.ACTION_UP)) {
            val now = android.os.SystemClock.uptimeMillis()
            window.dispatchInputEvent(
                KeyEvent(down, now, action, KeyEvent.KEYCODE_BACK, 0, 0, KeyCharacterMap.VIRTUAL_KEYBOARD, 0, 0, InputDevice.SOURCE_KEYBOARD),
            )
            idle()
        }
        run(20.milliseconds)
    }

    /** The dialog on screen, or an error. */
    fun dialog(): android.app.AlertDialog = org.robolectric.shadows.ShadowAlertDialog.getLatestAlertDialog()?.takeIf { it.isShowing }
        ?: throw AssertionError("no dialog on screen; visible: ${texts()}")

    /** Ends the Activity if the test left it alive (its window's surface released), as Android does when the app goes. */
    fun close() {
        if (::controller.isInitialized) controller.close()
        if (crashed.isNotEmpty()) throw AssertionError("the app would have crashed: ${crashed.first()}", crashed.first())
    }

    /** Lets [duration] of simulated time (or real time, in [realTime]) pass, the main looper (views, broadcasts) running along. */
    suspend fun run(duration: Duration) {
        var left = duration
        while (left > Duration.ZERO) {
            idle()
            if (realTime) {
                Thread.sleep(10)
                shadowOf(Looper.getMainLooper()).idleFor(java.time.Duration.ofMillis(10)) // the main thread's delays
            } else {
                delay(10.milliseconds)
            }
            left -= 10.milliseconds
        }
        idle()
    }

    /** Runs until [condition] holds, at most [limit] (of simulated time, or real time in [realTime]); fails with [what] otherwise. */
    suspend fun until(what: String, limit: Duration = 10.seconds, condition: () -> Boolean) {
        var waited = Duration.ZERO
        while (!condition()) {
            if (waited >= limit) throw AssertionError("$what: not within $limit of ${if (realTime) "real" else "simulated"} time")
            run(10.milliseconds)
            waited += 10.milliseconds
        }
    }

    fun idle() = shadowOf(Looper.getMainLooper()).idle()

    val root: View get() = activity.window.decorView

    /** The view showing exactly [text] (a button, a label), or an error naming what is on screen. */
    fun view(text: String): View = findText(root) { it == text } ?: throw AssertionError("no \"$text\" on screen; visible: ${texts()}")

    suspend fun click(text: String) {
        run(20.milliseconds)
        view(text).performClick()
        run(20.milliseconds)
    }

    /** True when a visible text on screen contains [part]. */
    fun shows(part: String): Boolean = texts().any { part in it }

    fun texts(): List<String> = buildList { collect(root, this) }

    private fun collect(v: View, out: MutableList<String>) {
        if (!v.isShown) return
        if (v is TextView && v.text.isNotEmpty()) out += v.text.toString()
        if (v is ViewGroup) for (i in 0 until v.childCount) collect(v.getChildAt(i), out)
    }

    private fun findText(v: View, match: (String) -> Boolean): View? {
        if (!v.isShown) return null
        if (v is TextView && match(v.text.toString())) return v
        if (v is ViewGroup) for (i in 0 until v.childCount) findText(v.getChildAt(i), match)?.let { return it }
        return null
    }

    /** The text field on screen whose hint (its label) contains [label]. */
    fun field(label: String): android.widget.EditText = buildList { collectFields(root, this) }.firstOrNull { label in (it.hint ?: "") }
        ?: throw AssertionError("no field \"$label\" on screen")

    private fun collectFields(v: View, out: MutableList<android.widget.EditText>) {
        if (!v.isShown) return
        if (v is android.widget.EditText) out += v
        if (v is ViewGroup) for (i in 0 until v.childCount) collectFields(v.getChildAt(i), out)
    }

    /** The first view of type [T] on screen. */
    inline fun <reified T : View> find(): T = findType(root, T::class.java) ?: throw AssertionError("no ${T::class.simpleName} on screen")

    fun <T : View> findType(v: View, type: Class<T>): T? {
        if (type.isInstance(v) && v.isShown) return type.cast(v)
        if (v is ViewGroup) for (i in 0 until v.childCount) findType(v.getChildAt(i), type)?.let { return it }
        return null
    }

    /** A finger on [view] at ([fx], [fy]) of its size (0..1). */
    suspend fun touch(view: View, action: Int, fx: Float, fy: Float) {
        val now = android.os.SystemClock.uptimeMillis()
        val e = MotionEvent.obtain(now, now, action, view.width * fx, view.height * fy, 0)
        view.dispatchTouchEvent(e)
        e.recycle()
        run(10.milliseconds)
    }

    /** A thumb lands on the joystick [stick]'s knob (its centre) and pushes it to ([fx], [fy]) of the pad's size. */
    suspend fun push(stick: View, fx: Float, fy: Float) {
        touch(stick, MotionEvent.ACTION_DOWN, 0.5f, 0.5f)
        touch(stick, MotionEvent.ACTION_MOVE, fx, fy)
    }

    /**
     * A finger lands on [on] at ([fromX], [fromY]) of its size and slides vertically to [toY], in steps, as a scroll
     * does; the events go in at the window, so every view on the way (a ScrollView above) sees them as on a phone.
     */
    suspend fun swipe(on: View, fromX: Float, fromY: Float, toY: Float) {
        val at = IntArray(2).also { on.getLocationInWindow(it) }
        val x = at[0] + on.width * fromX
        val down = android.os.SystemClock.uptimeMillis()
        fun send(action: Int, fy: Float) {
            val e = MotionEvent.obtain(down, android.os.SystemClock.uptimeMillis(), action, x, at[1] + on.height * fy, 0)
            root.dispatchTouchEvent(e)
            e.recycle()
        }
        send(MotionEvent.ACTION_DOWN, fromY)
        for (i in 1..10) {
            run(16.milliseconds)
            send(MotionEvent.ACTION_MOVE, fromY + (toY - fromY) * i / 10)
        }
        send(MotionEvent.ACTION_UP, toY)
        run(10.milliseconds)
    }

    /**
     * Draws the whole window as the phone shows it at rest into docs/images/android-[name].png, and returns the picture.
     *
     * Animated drawables are shown at their end: a phone runs them on its RenderThread (a radio button's dot grows in
     * a few hundred milliseconds), Robolectric has none, so they would stay at their first frame (a ring, no dot).
     */
    suspend fun screenshot(name: String): Bitmap {
        run(20.milliseconds)
        val v = root
        v.jumpDrawablesToCurrentState()
        val bitmap = Bitmap.createBitmap(v.width, v.height, Bitmap.Config.ARGB_8888)
        v.draw(Canvas(bitmap))
        val dir = File(System.getProperty("pocketbot.screenshots.dir") ?: "target/screenshots").apply { mkdirs() }
        File(dir, "android-$name.png").outputStream().use { bitmap.compress(Bitmap.CompressFormat.PNG, 100, it) }
        return bitmap
    }

    /** The colour [picture] (of the whole window) has at the centre of [button]'s mark: a radio button's dot, if drawn. */
    fun markCentre(picture: Bitmap, button: CompoundButton): Int {
        val at = IntArray(2)
        button.getLocationInWindow(at)
        val mark = button.buttonDrawable?.bounds ?: throw AssertionError("$button draws no mark")
        return picture.getPixel(at[0] + mark.centerX(), at[1] + mark.centerY())
    }
}

/** Runs [block] with the app against an emulator of [world] with one robot, on simulated time. */
fun withApp(world: String = "round", limit: Duration = 120.seconds, block: suspend AppHarness.() -> Unit) {
    Emulator.local(robots = 1, world = world).use { emu ->
        emu.runSimulated(limit) {
            // The app's scope is not the run's: its collectors never end on their own, the run must.
            val app = CoroutineScope(coroutineContext.minusKey(Job) + SupervisorJob())
            val harness = AppHarness(emu, app)
            try {
                harness.block()
            } finally {
                harness.close()
                app.cancel()
            }
        }
    }
}

/** Connects the emulator's robot through the robot list, as a person does. */
suspend fun AppHarness.connectRobot() {
    launch()
    click("Find robots")
    until("the robot is found") { model.found.value.isNotEmpty() }
    click("Connect")
    until("the robot is connected") { model.session.value != null }
    run(300.milliseconds)
}

/**
 * Runs [block] with the app on the main thread as on a phone, in real time, against [emulator] running on its own
 * thread and reached over real sockets; the app finds robots only where the test points it (Bluetooth, the network).
 */
fun withRealTimeApp(emulator: Emulator, block: suspend AppHarness.() -> Unit) {
    val job = SupervisorJob()
    val app = CoroutineScope(job + Dispatchers.Main.immediate)
    val harness = AppHarness(emulator, app, sources = emptyMap(), realTime = true)
    try {
        runBlocking { harness.block() }
    } finally {
        harness.close()
        app.cancel()
        // Coroutines on the main thread end only when its looper runs; then the robot, bound to the app's scope, closes
        // its link, and no reconnect of this test's robot reaches into the next test.
        runBlocking { withTimeout(10.seconds) { while (!job.isCompleted) { harness.idle(); delay(5) } } }
    }
}
