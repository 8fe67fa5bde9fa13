package org.pocketbot.android

import android.app.Notification
import android.app.NotificationChannel
import android.app.NotificationManager
import android.app.PendingIntent
import android.app.Service
import android.content.Context
import android.content.Intent
import android.content.pm.ServiceInfo
import android.graphics.drawable.Icon
import android.os.Build
import android.os.IBinder
import kotlinx.coroutines.Job
import kotlinx.coroutines.flow.distinctUntilChanged
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.launch
import org.pocketbot.android.model.AppModel

/**
 * A foreground service while a robot is connected: it keeps the app's process (and so the connection, which lives in
 * the [AppModel]) alive in the background, and shows a notification that leads back to the app, with *Stop robot*
 * and *Disconnect* on it. It goes to the foreground on every start, then ends itself once no robot is connected: it
 * is never stopped from outside before it got there (Android ends an app for that). When the user swipes the app
 * away from the recent apps, the robot is stopped and disconnected.
 */
class ConnectionService : Service() {
    private var watch: Job? = null

    override fun onBind(intent: Intent?): IBinder? = null

    override fun onStartCommand(intent: Intent?, flags: Int, startId: Int): Int {
        val model = (application as ModelOwner).model
        when (intent?.action) {
            ACTION_STOP_ROBOT -> model.session.value?.stopRobot()
            ACTION_DISCONNECT -> model.disconnect()
        }
        if (!goForeground(model.session.value?.name ?: intent?.getStringExtra(EXTRA_ROBOT) ?: "a robot")) {
            stopSelf()
            return START_NOT_STICKY
        }
        if (watch == null) watch = model.scope.launch {
            model.session.map { it?.name }.distinctUntilChanged().collect { robot ->
                if (robot == null) {
                    stopForeground(STOP_FOREGROUND_REMOVE)
                    stopSelf()
                } else {
                    goForeground(robot)
                }
            }
        }
        return START_NOT_STICKY
    }

    override fun onDestroy() {
        watch?.cancel()
        super.onDestroy()
    }

    override fun onTaskRemoved(rootIntent: Intent?) {
        (application as ModelOwner).model.closeApp()
    }

    /** Shows the notification for [robot] and keeps the service in the foreground; false when Android does not allow it. */
    private fun goForeground(robot: String): Boolean = try {
        if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.Q) {
            startForeground(NOTIFICATION_ID, notification(robot), ServiceInfo.FOREGROUND_SERVICE_TYPE_CONNECTED_DEVICE)
        } else {
            startForeground(NOTIFICATION_ID, notification(robot))
        }
        true
    } catch (e: RuntimeException) {
        false
    }

    private fun notification(robot: String): Notification {
        getSystemService(NotificationManager::class.java)
            ?.createNotificationChannel(NotificationChannel(CHANNEL, "Robot connection", NotificationManager.IMPORTANCE_LOW))
        val open = PendingIntent.getActivity(
            this, 0, Intent(this, MainActivity::class.java).addFlags(Intent.FLAG_ACTIVITY_SINGLE_TOP),
            PendingIntent.FLAG_IMMUTABLE,
        )
        fun action(icon: Int, title: String, action: String) = Notification.Action.Builder(
            Icon.createWithResource(this, icon), title,
            PendingIntent.getService(this, action.hashCode(), Intent(this, ConnectionService::class.java).setAction(action), PendingIntent.FLAG_IMMUTABLE),
        ).build()
        return Notification.Builder(this, CHANNEL)
            .setSmallIcon(android.R.drawable.stat_sys_data_bluetooth)
            .setContentTitle("Connected to $robot")
            .setContentText("PocketBot keeps the robot connected. Tap to open.")
            .setContentIntent(open)
            .addAction(action(android.R.drawable.ic_media_pause, "Stop robot", ACTION_STOP_ROBOT))
            .addAction(action(android.R.drawable.ic_menu_close_clear_cancel, "Disconnect", ACTION_DISCONNECT))
            .setOngoing(true)
            .build()
    }

    /**
     * Starts the service whenever a robot is connected. Android 12 and later refuse to start a foreground service
     * while the app is in the background (a connection that finished there): then [retry], called when the app
     * comes to the foreground, starts it.
     */
    class Keeper(private val context: Context, private val model: AppModel) {
        private var waiting: String? = null

        init {
            model.scope.launch {
                model.session.map { it?.name }.distinctUntilChanged().collect { robot ->
                    waiting = null
                    if (robot != null) start(robot)
                }
            }
        }

        /** The app is in the foreground: start the service Android refused before, if a robot is still connected. */
        fun retry() {
            val robot = waiting ?: return
            if (model.session.value?.name == robot) start(robot) else waiting = null
        }

        private fun start(robot: String) {
            waiting = try {
                context.startForegroundService(Intent(context, ConnectionService::class.java).putExtra(EXTRA_ROBOT, robot))
                null
            } catch (e: IllegalStateException) {
                robot // ForegroundServiceStartNotAllowedException: the app is in the background
            }
        }
    }

    companion object {
        private const val CHANNEL = "connection"
        private const val NOTIFICATION_ID = 1
        const val EXTRA_ROBOT = "robot"
        const val ACTION_STOP_ROBOT = "org.pocketbot.android.STOP_ROBOT"
        const val ACTION_DISCONNECT = "org.pocketbot.android.DISCONNECT"
    }
}
