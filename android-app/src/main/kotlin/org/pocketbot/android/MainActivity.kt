package org.pocketbot.android

import android.app.Activity
import android.bluetooth.BluetoothAdapter
import android.content.Intent
import android.graphics.Color
import android.net.Uri
import android.os.Bundle
import android.provider.Settings
import android.view.Gravity
import android.view.View
import android.view.ViewGroup
import android.widget.FrameLayout
import android.widget.LinearLayout
import android.widget.TextView
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Job
import kotlinx.coroutines.SupervisorJob
import kotlinx.coroutines.cancel
import kotlinx.coroutines.flow.collectLatest
import kotlinx.coroutines.flow.combine
import kotlinx.coroutines.launch
import kotlinx.coroutines.plus
import org.pocketbot.android.model.AppModel
import org.pocketbot.android.model.Notice
import org.pocketbot.android.model.RobotSession
import org.pocketbot.android.model.Screen
import org.pocketbot.android.ui.BluetoothActions
import org.pocketbot.android.ui.ButtonStyle
import org.pocketbot.android.ui.Palette
import org.pocketbot.android.ui.button
import org.pocketbot.android.ui.calibrationScreen
import org.pocketbot.android.ui.dp
import org.pocketbot.android.ui.driveScreen
import org.pocketbot.android.ui.followScreen
import org.pocketbot.android.ui.horizontal
import org.pocketbot.android.ui.noRobotScreen
import org.pocketbot.android.ui.pathScreen
import org.pocketbot.android.ui.robotsScreen
import org.pocketbot.android.ui.rounded
import org.pocketbot.android.ui.sensorScreen
import org.pocketbot.android.ui.text
import org.pocketbot.android.ui.vertical
import org.pocketbot.android.ui.weight

/**
 * The one Activity: a status bar with the robot's battery and link (always visible) and a stop button, a notice when
 * there is something to tell, the current screen, and the navigation bar. It only draws the [AppModel] (which lives
 * in the Application) and forwards input; recreating it (rotation) loses nothing.
 */
class MainActivity : Activity(), BluetoothActions {
    private lateinit var owner: ModelOwner
    private val model: AppModel get() = owner.model
    private lateinit var views: CoroutineScope
    private var screenJob: Job? = null
    private lateinit var content: FrameLayout

    override fun onCreate(savedInstanceState: Bundle?) {
        super.onCreate(savedInstanceState)
        owner = application as ModelOwner
        views = model.scope + SupervisorJob(model.scope.coroutineContext[Job])
        window.statusBarColor = Palette.PRIMARY_DARK
        content = FrameLayout(this)
        setContentView(vertical(0, topBar(), noticeBar(), content.apply { layoutParams = LinearLayout.LayoutParams(ViewGroup.LayoutParams.MATCH_PARENT, 0, 1f) }, navigationBar()).apply {
            setBackgroundColor(Palette.BACKGROUND)
        })
        views.launch { combine(model.screen, model.session) { s, r -> s to r }.collect { (screen, session) -> show(screen, session) } }
    }

    override fun onStart() {
        super.onStart()
        owner.bluetoothAccess.refresh()
    }

    override fun onStop() {
        super.onStop()
        // Dead-man: the joystick needs a finger on the screen; an app in the background has none.
        model.session.value?.joystick?.release()
    }

    override fun onDestroy() {
        views.cancel()
        // Leaving the app (not rotating it): the robot stops and disconnects.
        if (isFinishing && !isChangingConfigurations) model.closeApp()
        super.onDestroy()
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

    /** App name, the robot's name, battery and link, and a stop button while a robot is connected. */
    private fun topBar(): View {
        val title = text("PocketBot", 20f, Color.WHITE, bold = true)
        val robot = text("no robot connected", 13f, Color.argb(210, 255, 255, 255))
        val battery = text("", 13f, Color.WHITE).apply { tag = "battery" }
        val link = text("", 13f, Color.WHITE).apply { tag = "link" }
        val stop = button("STOP", ButtonStyle.DANGER) { model.session.value?.stopRobot() }
        val bar = horizontal(
            vertical(0, title, robot).apply { layoutParams = weight() },
            vertical(0, battery, link).apply { gravity = Gravity.END; setPadding(0, 0, dp(10), 0) },
            stop,
        ).apply {
            setBackgroundColor(Palette.PRIMARY)
            setPadding(dp(16), dp(10), dp(12), dp(10))
            elevation = dp(4).toFloat()
        }
        views.launch {
            model.session.collectLatest { session ->
                stop.visibility = if (session == null) View.GONE else View.VISIBLE
                battery.visibility = stop.visibility
                link.visibility = stop.visibility
                if (session == null) robot.text = "no robot connected"
                session?.status?.collect { s ->
                    robot.text = s.name
                    battery.text = if (s.batteryV > 0) "▮ %d%% · %.2f V".format(s.batteryPercent, s.batteryV) else "▮ —"
                    battery.setTextColor(if (s.batteryV > 0 && s.batteryPercent < 15) Color.rgb(255, 205, 120) else Color.WHITE)
                    link.text = "${if (s.linkUp) "●" else "○"} ${s.linkText}"
                    link.setTextColor(if (s.linkUp) Color.rgb(170, 240, 190) else Color.rgb(255, 180, 170))
                }
            }
        }
        return bar
    }

    private fun noticeBar(): View {
        val message = text("", 14f, Palette.TEXT).apply { layoutParams = weight() }
        val close = text("✕", 18f, Palette.TEXT_SOFT).apply {
            setPadding(dp(12), dp(4), dp(4), dp(4))
            setOnClickListener { model.dismissNotice() }
        }
        val bar = horizontal(message, close).apply { setPadding(dp(16), dp(10), dp(12), dp(10)) }
        views.launch {
            model.notice.collect { n ->
                bar.visibility = if (n == null) View.GONE else View.VISIBLE
                if (n != null) {
                    message.text = n.text
                    bar.background = rounded(this@MainActivity, when (n.kind) {
                        Notice.Kind.INFO -> Color.rgb(0xE3, 0xF2, 0xE8)
                        Notice.Kind.WARNING -> Color.rgb(0xFF, 0xF3, 0xD6)
                        Notice.Kind.ERROR -> Color.rgb(0xFD, 0xE4, 0xE1)
                    }, 0)
                }
            }
        }
        return bar
    }

    private fun navigationBar(): View {
        val bar = horizontal().apply {
            setBackgroundColor(Color.WHITE)
            elevation = dp(8).toFloat()
            setPadding(dp(4), dp(6), dp(4), dp(8))
        }
        val tabs = Screen.entries.associateWith { screen ->
            TextView(this).apply {
                text = screen.title
                textSize = 12f
                gravity = Gravity.CENTER
                setPadding(0, dp(8), 0, dp(8))
                setOnClickListener { model.show(screen) }
                layoutParams = weight()
            }
        }
        tabs.values.forEach { bar.addView(it) }
        views.launch {
            model.screen.collect { current ->
                for ((screen, tab) in tabs) {
                    val on = screen == current
                    tab.setTextColor(if (on) Palette.PRIMARY else Palette.TEXT_SOFT)
                    tab.typeface = android.graphics.Typeface.create(android.graphics.Typeface.DEFAULT, if (on) android.graphics.Typeface.BOLD else android.graphics.Typeface.NORMAL)
                    tab.background = if (on) rounded(this@MainActivity, Palette.PRIMARY_SOFT, 16) else null
                }
            }
        }
        return bar
    }

    // ---- Bluetooth: permissions, the switch, the settings ----

    override fun askPermission() = requestPermissions(owner.bluetoothAccess.permissions, REQUEST_PERMISSIONS)

    override fun canAskAgain(): Boolean = owner.bluetoothAccess.permissions.any { shouldShowRequestPermissionRationale(it) }

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

    override fun onRequestPermissionsResult(requestCode: Int, permissions: Array<out String>, grantResults: IntArray) {
        super.onRequestPermissionsResult(requestCode, permissions, grantResults)
        if (requestCode != REQUEST_PERMISSIONS) return
        owner.bluetoothAccess.permissionsAnswered()
        if (owner.bluetoothAccess.status.value == org.pocketbot.android.model.BluetoothStatus.READY) model.scan()
    }

    @Deprecated("the framework Activity's result callback")
    override fun onActivityResult(requestCode: Int, resultCode: Int, data: Intent?) {
        @Suppress("DEPRECATION")
        super.onActivityResult(requestCode, resultCode, data)
        if (requestCode != REQUEST_ENABLE) return
        owner.bluetoothAccess.refresh()
        if (owner.bluetoothAccess.status.value == org.pocketbot.android.model.BluetoothStatus.READY) model.scan()
    }

    private companion object {
        const val REQUEST_PERMISSIONS = 1
        const val REQUEST_ENABLE = 2
    }
}
