package org.pocketbot.android

import android.Manifest
import android.app.Activity
import android.app.AlertDialog
import android.bluetooth.BluetoothAdapter
import android.content.Intent
import android.content.pm.PackageManager
import android.graphics.Color
import android.graphics.Typeface
import android.net.Uri
import android.os.Build
import android.os.Bundle
import android.provider.Settings
import android.view.Gravity
import android.view.View
import android.view.ViewGroup
import android.view.WindowInsets
import android.view.WindowInsetsController
import android.view.WindowManager
import android.widget.FrameLayout
import android.widget.HorizontalScrollView
import android.widget.LinearLayout
import android.widget.TextView
import android.window.OnBackInvokedCallback
import android.window.OnBackInvokedDispatcher
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.collectLatest
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.launch
import kotlinx.coroutines.plus
import org.pocketbot.android.model.AppModel
import org.pocketbot.android.model.BluetoothStatus
import org.pocketbot.android.model.Notice
import org.pocketbot.android.model.RobotSession
import org.pocketbot.android.model.Screen
import org.pocketbot.android.ui.BluetoothActions
import org.pocketbot.android.ui.ButtonStyle
import org.pocketbot.android.ui.TOUCH_TARGET_DP
import org.pocketbot.android.ui.button
import org.pocketbot.android.ui.calibrationScreen
import org.pocketbot.android.ui.dp
import org.pocketbot.android.ui.heading
import org.pocketbot.android.ui.driveScreen
import org.pocketbot.android.ui.followScreen
import org.pocketbot.android.ui.horizontal
import org.pocketbot.android.ui.noRobotScreen
import org.pocketbot.android.ui.palette
import org.pocketbot.android.ui.pathScreen
import org.pocketbot.android.ui.robotsScreen
import org.pocketbot.android.ui.rounded
import org.pocketbot.android.ui.sensorScreen
import org.pocketbot.android.ui.text
import org.pocketbot.android.ui.vertical
import org.pocketbot.android.ui.weight
import kotlin.math.max

/**
 * The one Activity: a status bar with the robot's battery and link (always visible) and a stop button, a notice when
 * there is something to tell, the current screen, and the navigation bar. It only draws the [AppModel] (which lives
 * in the Application) and forwards input; recreating it (rotation) loses nothing. It draws edge to edge (as Android 15
 * requires) and keeps its bars clear of the system bars, the display cutout and the keyboard.
 *
 * **Back, while a robot is connected, stops the robot and asks** whether to disconnect and leave or to stay: since
 * Android 12, Back on this (launcher) Activity would only move the app to the background and leave the robot
 * driving. With no robot connected, Back does what Android does.
 */
class MainActivity : Activity(), BluetoothActions {
    private lateinit var owner: ModelOwner
    private val model: AppModel get() = owner.model
    private lateinit var views: CoroutineScope
    private var screenJob: Job? = null
    private lateinit var content: FrameLayout
    private var backCallback: Any? = null // an OnBackInvokedCallback on Android 13 and later
    private var leaveDialog: AlertDialog? = null

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        owner = application as ModelOwner
        views = model.scope + SupervisorJob(model.scope.coroutineContext[Job])
        content = FrameLayout(this)
        val top = topBar()
        val tabs = navigationBar()
        val root = vertical(0, top, noticeBar(), content.apply { layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, 0, 1f) }, tabs).apply {
            setBackgroundColor(palette.BACKGROUND)
        }
        root.setOnApplyWindowInsetsListener { _, insets ->
            val (bars, keyboard) = barsAndKeyboard(insets)
            top.setPadding(bars[0] + dp(16), bars[1] + dp(10), bars[2] + dp(12), dp(10))
            tabs.setPadding(bars[0], 0, bars[2], bars[3])
            // The keyboard covers the navigation bar: the screen ends above it.
            root.setPadding(0, 0, 0, max(0, keyboard - bars[3]))
            insets
        }
        setContentView(root)
        drawEdgeToEdge()
        views.launch { combine(model.screen, model.session) { s, r -> s to r }.collect { (screen, session) -> show(screen, session) } }
        views.launch {
            model.session.collectLatest { session ->
                followBack(session)
                if (session == null) return@collectLatest window.clearFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON)
                askForNotifications()
                // The screen stays on while the robot drives under the user's hand.
                session.driving.collect { driving ->
                    if (driving) window.addFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON) else window.clearFlags(WindowManager.LayoutParams.FLAG_KEEP_SCREEN_ON)
                }
            }
        }
    }

    override fun onStart() {
        super.onStart()
        owner.bluetoothAccess.refresh()
        owner.connectionService.retry()
    }

    override fun onStop() {
        super.onStop()
        // Dead-man: the joystick needs a finger on the screen; an app in the background has none.
        model.session.value?.joystick?.release()
    }

    override fun onDestroy() {
        views.cancel()
        leaveDialog?.dismiss()
        // Leaving the app (not rotating it): the robot stops and disconnects.
        if (isFinishing && !isChangingConfigurations) model.closeApp()
        super.onDestroy()
    }

    // ---- Back ----

    /** Android 12 and earlier deliver Back here (Android 13 and later to the callback of [followBack]). */
    @Deprecated("the framework's Back before OnBackInvokedCallback")
    override fun onBackPressed() {
        if (model.session.value != null) stopAndAskToLeave() else @Suppress("DEPRECATION") super.onBackPressed()
    }

    /** On Android 13 and later, Back comes to the app only while a robot is connected; otherwise Android handles it. */
    private fun followBack(session: RobotSession?) {
        if (Build.VERSION.SDK_INT < Build.VERSION_CODES.TIRAMISU) return
        val callback = backCallback as OnBackInvokedCallback?
        if (session != null && callback == null) {
            backCallback = OnBackInvokedCallback { stopAndAskToLeave() }.also {
                onBackInvokedDispatcher.registerOnBackInvokedCallback(OnBackInvokedDispatcher.PRIORITY_DEFAULT, it)
            }
        } else if (session == null && callback != null) {
            onBackInvokedDispatcher.unregisterOnBackInvokedCallback(callback)
            backCallback = null
        }
    }

    /** Back with a robot connected: the robot stops at once, then the user chooses to leave (disconnecting it) or stay. */
    private fun stopAndAskToLeave() {
        val session = model.session.value ?: return
        session.stopRobot()
        if (leaveDialog?.isShowing == true) return
        leaveDialog = AlertDialog.Builder(this)
            .setTitle("Leave PocketBot?")
            .setMessage("${session.name} is stopped. Disconnect it and leave, or stay connected?")
            .setPositiveButton("Disconnect and leave") { _, _ ->
                model.closeApp()
                finish()
            }
            .setNegativeButton("Stay", null)
            .show()
    }

    // ---- Window ----

    @Suppress("DEPRECATION") // the pre-Android 11 flags and bar colours, for the versions that need them
    private fun drawEdgeToEdge() {
        window.statusBarColor = Color.TRANSPARENT
        window.navigationBarColor = Color.TRANSPARENT
        val light = !palette.night
        if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.R) {
            window.setDecorFitsSystemWindows(false)
            // Light status bar icons on the blue bar; dark navigation icons on the light tab bar.
            window.insetsController?.setSystemBarsAppearance(
                if (light) WindowInsetsController.APPEARANCE_LIGHT_NAVIGATION_BARS else 0,
                WindowInsetsController.APPEARANCE_LIGHT_NAVIGATION_BARS or WindowInsetsController.APPEARANCE_LIGHT_STATUS_BARS,
            )
        } else {
            window.decorView.systemUiVisibility = View.SYSTEM_UI_FLAG_LAYOUT_STABLE or View.SYSTEM_UI_FLAG_LAYOUT_FULLSCREEN or
                View.SYSTEM_UI_FLAG_LAYOUT_HIDE_NAVIGATION or (if (light) View.SYSTEM_UI_FLAG_LIGHT_NAVIGATION_BAR else 0)
        }
    }

    /** The system bars and display cutout (left, top, right, bottom) and the keyboard's height, in pixels. */
    @Suppress("DEPRECATION")
    private fun barsAndKeyboard(insets: WindowInsets): Pair<IntArray, Int> =
        if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.R) {
            val bars = insets.getInsets(WindowInsets.Type.systemBars() or WindowInsets.Type.displayCutout())
            intArrayOf(bars.left, bars.top, bars.right, bars.bottom) to insets.getInsets(WindowInsets.Type.ime()).bottom
        } else {
            intArrayOf(insets.systemWindowInsetLeft, insets.systemWindowInsetTop, insets.systemWindowInsetRight, insets.stableInsetBottom) to
                insets.systemWindowInsetBottom
        }

    private fun show(screen: Screen, session: RobotSession?) {
        screenJob?.cancel()
        val job = SupervisorJob(views.coroutineContext[Job])
        screenJob = job
        val scope = views + job
        content.removeAllViews()
        content.addView(
            when {
                screen == Screen.ROBOTS -> robotsScreen(this, model, this, scope)
                session == null -> noRobotScreen(this, model)
                else -> when (screen) {
                    Screen.SENSOR -> sensorScreen(this, session, scope)
                    Screen.CALIBRATE -> calibrationScreen(this, session, scope)
                    Screen.DRIVE -> driveScreen(this, session, scope)
                    Screen.FOLLOW -> followScreen(this, session, scope)
                    Screen.PATH -> pathScreen(this, session, scope)
                    Screen.ROBOTS -> error("shown above")
                }
            },
            FrameLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, ViewGroup.LayoutParams.MATCH_PARENT),
        )
    }

    /** App name, the robot's name, battery and link (greyed with their age when not live), and a stop button. */
    private fun topBar(): View {
        val p = palette
        val title = text("PocketBot", 20f, p.BAR_TEXT, bold = true).apply { heading() }
        val robot = text("no robot connected", 14f, p.BAR_SOFT)
        val battery = text("", 14f, p.BAR_TEXT).apply { tag = "battery" }
        val link = text("", 14f, p.BAR_TEXT).apply { tag = "link" }
        val stop = button("STOP", ButtonStyle.DANGER) { model.session.value?.stopRobot() }.apply { contentDescription = "Stop the robot" }
        // Large fonts (130 % and more) stack the robot's name and state under the title, so no word is cut.
        val bar = if (resources.configuration.fontScale < 1.3f) horizontal(
            vertical(0, title, robot).apply { layoutParams = weight() },
            vertical(0, battery, link).apply { gravity = Gravity.END; setPadding(0, 0, dp(10), 0) },
            stop,
        ) else vertical(0, horizontal(title.apply { layoutParams = weight() }, stop), robot, battery, link)
        bar.setBackgroundColor(p.BAR)
        bar.elevation = dp(4).toFloat()
        views.launch {
            model.session.collectLatest { session ->
                stop.visibility = if (session == null) View.GONE else View.VISIBLE
                battery.visibility = stop.visibility
                link.visibility = stop.visibility
                if (session == null) robot.text = "no robot connected"
                session ?: return@collectLatest
                combine(session.status, session.freshness) { s, f -> s to f }.collect { (s, f) ->
                    robot.text = s.name
                    val age = if (f.live) "" else " · ${f.age} ago"
                    battery.text = if (s.batteryV > 0) "▮ %d%% · %.2f V%s".format(s.batteryPercent, s.batteryV, age) else "▮ —"
                    battery.setTextColor(if (!f.live) p.BAR_SOFT else if (s.batteryV > 0 && s.batteryPercent < 15) p.BAR_BAD else p.BAR_TEXT)
                    link.text = "${if (s.linkUp) "●" else "○"} ${s.linkText}"
                    link.setTextColor(if (s.linkUp) p.BAR_GOOD else p.BAR_BAD)
                }
            }
        }
        return bar
    }

    private fun noticeBar(): View {
        val message = text("", 14f, palette.TEXT).apply {
            layoutParams = weight()
            accessibilityLiveRegion = View.ACCESSIBILITY_LIVE_REGION_POLITE
        }
        val close = text("✕", 18f, palette.TEXT_SOFT).apply {
            gravity = Gravity.CENTER
            minWidth = dp(TOUCH_TARGET_DP)
            minHeight = dp(TOUCH_TARGET_DP)
            contentDescription = "Dismiss"
            setOnClickListener { model.dismissNotice() }
        }
        val bar = horizontal(message, close).apply { setPadding(dp(16), dp(4), dp(4), dp(4)) }
        views.launch {
            model.notice.collect { n ->
                bar.visibility = if (n == null) View.GONE else View.VISIBLE
                if (n != null) {
                    message.text = n.text
                    bar.background = rounded(this@MainActivity, when (n.kind) {
                        Notice.Kind.INFO -> palette.NOTICE_INFO
                        Notice.Kind.WARNING -> palette.NOTICE_WARNING
                        Notice.Kind.ERROR -> palette.NOTICE_ERROR
                    }, 0)
                }
            }
        }
        return bar
    }

    /** The screens' tabs: they share the width, and scroll sideways where the largest font makes them wider. */
    private fun navigationBar(): View {
        val p = palette
        val row = horizontal().apply { setPadding(dp(4), dp(4), dp(4), dp(4)) }
        val tabs = Screen.entries.associateWith { screen ->
            TextView(this).apply {
                text = screen.title
                textSize = 13f
                gravity = Gravity.CENTER
                isSingleLine = true
                minHeight = dp(TOUCH_TARGET_DP)
                minWidth = dp(TOUCH_TARGET_DP)
                setPadding(dp(8), 0, dp(8), 0)
                setOnClickListener { model.show(screen) }
                layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.WRAP_CONTENT, ViewGroup.LayoutParams.WRAP_CONTENT, 1f)
            }
        }
        tabs.values.forEach { row.addView(it) }
        views.launch {
            model.screen.collect { current ->
                for ((screen, tab) in tabs) {
                    val on = screen == current
                    tab.isSelected = on
                    tab.setTextColor(if (on) p.PRIMARY else p.TEXT_SOFT)
                    tab.typeface = Typeface.create(Typeface.DEFAULT, if (on) Typeface.BOLD else Typeface.NORMAL)
                    tab.background = if (on) rounded(this@MainActivity, p.PRIMARY_SOFT, 16) else null
                }
            }
        }
        return HorizontalScrollView(this).apply {
            isFillViewport = true
            isHorizontalScrollBarEnabled = false
            setBackgroundColor(p.CARD)
            elevation = dp(8).toFloat()
            addView(row)
        }
    }

    // ---- Permissions: Bluetooth, notifications; the Bluetooth switch ----

    override fun askPermission() = requestPermissions(owner.bluetoothAccess.permissions, REQUEST_PERMISSIONS)

    override fun openAppSettings() {
        startActivity(Intent(Settings.ACTION_APPLICATION_DETAILS_SETTINGS, Uri.fromParts("package", packageName, null)))
    }

    override fun turnBluetoothOn() {
        try {
            @Suppress("DEPRECATION") // the system's "turn Bluetooth on?" dialog; its replacement needs androidx
            startActivityForResult(Intent(BluetoothAdapter.ACTION_REQUEST_ENABLE), REQUEST_ENABLE)
        } catch (e: SecurityException) {
            askPermission()
        }
    }

    /** Android 13 on: the connection's notification (and its Stop button) needs the user's permission; asked once. */
    private fun askForNotifications() {
        if (Build.VERSION.SDK_INT < Build.VERSION_CODES.TIRAMISU || model.askedForNotifications) return
        if (checkSelfPermission(Manifest.permission.POST_NOTIFICATIONS) == PackageManager.PERMISSION_GRANTED) return
        model.askedForNotifications = true
        requestPermissions(arrayOf(Manifest.permission.POST_NOTIFICATIONS), REQUEST_NOTIFICATIONS)
    }

    override fun onRequestPermissionsResult(requestCode: Int, permissions: Array<out String>, grantResults: IntArray) {
        super.onRequestPermissionsResult(requestCode, permissions, grantResults)
        when (requestCode) {
            REQUEST_PERMISSIONS -> {
                // Whether Android would show its dialog again: not after a second "Don't allow".
                owner.bluetoothAccess.permissionsAnswered(canAskAgain = permissions.any { shouldShowRequestPermissionRationale(it) })
                if (owner.bluetoothAccess.status.value == BluetoothStatus.READY) model.scan()
            }
            REQUEST_NOTIFICATIONS -> if (grantResults.any { it != PackageManager.PERMISSION_GRANTED }) model.tell(
                "Notifications are off: while PocketBot is in the background, Android shows no \"Connected to\" notification " +
                    "and no Stop button for the robot. Allow notifications in the app's settings to have them.",
                Notice.Kind.WARNING,
            )
        }
    }

    @Deprecated("the framework Activity's result callback")
    override fun onActivityResult(requestCode: Int, resultCode: Int, data: Intent?) {
        @Suppress("DEPRECATION")
        super.onActivityResult(requestCode, resultCode, data)
        if (requestCode != REQUEST_ENABLE) return
        owner.bluetoothAccess.refresh()
        if (owner.bluetoothAccess.status.value == BluetoothStatus.READY) model.scan()
    }

    private companion object {
        const val REQUEST_PERMISSIONS = 1
        const val REQUEST_ENABLE = 2
        const val REQUEST_NOTIFICATIONS = 3
    }
}
