package org.pocketbot.android

import android.app.Notification
import android.app.NotificationChannel
import android.app.NotificationManager
import android.app.PendingIntent
import android.app.Service
import android.content.Context
import android.content.Intent
import android.content.pm.ServiceInfo
import android.os.Build
import android.os.IBinder
import kotlinx.coroutines.flow.distinctUntilChanged
import kotlinx.coroutines.flow.map
import kotlinx.coroutines.launch
import org.pocketbot.android.model.AppModel

/**
 * A foreground service while a robot is connected: it keeps the app's process (and so the connection, which lives in
 * the [AppModel]) alive in the background, and shows a notification that leads back to the app. When the user
 * swipes the app away from the recent apps, the robot is stopped and disconnected.
 */
class ConnectionService : Service() {
    override fun onBind(intent: Intent?): IBinder? = null

    override fun onStartCommand(intent: Intent?, flags: Int, startId: Int): Int {
        val name = intent?.getStringExtra(EXTRA_ROBOT) ?: "a robot"
        val notification = notification(name)
        try {
            if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.Q) {
                startForeground(NOTIFICATION_ID, notification, ServiceInfo.FOREGROUND_SERVICE_TYPE_CONNECTED_DEVICE)
            } else {
                startForeground(NOTIFICATION_ID, notification)
            }
        } catch (e: RuntimeException) {
            // Not allowed now (started from the background): the connection lives on as long as the process does.
            stopSelf()
        }
        return START_NOT_STICKY
    }

    override fun onTaskRemoved(rootIntent: Intent?) {
        (application as ModelOwner).model.closeApp()
        stopSelf()
    }

    private fun notification(robot: String): Notification {
        val manager = getSystemService(NotificationManager::class.java)
        manager.createNotificationChannel(NotificationChannel(CHANNEL, "Robot connection", NotificationManager.IMPORTANCE_LOW))
        val open = PendingIntent.getActivity(
            this, 0, Intent(this, MainActivity::class.java).addFlags(Intent.FLAG_ACTIVITY_SINGLE_TOP),
            PendingIntent.FLAG_IMMUTABLE,
        )
        return Notification.Builder(this, CHANNEL)
            .setSmallIcon(android.R.drawable.stat_sys_data_bluetooth)
            .setContentTitle("Connected to $robot")
            .setContentText("PocketBot keeps the robot connected. Tap to open.")
            .setContentIntent(open)
            .setOngoing(true)
            .build()
    }

    companion object {
        private const val CHANNEL = "connection"
        private const val NOTIFICATION_ID = 1
        private const val EXTRA_ROBOT = "robot"

        /** Runs the service while [model] has a connected robot. */
        fun follow(context: Context, model: AppModel) {
            model.scope.launch {
                var started = false
                model.session.map { it?.name }.distinctUntilChanged().collect { robot ->
                    val intent = Intent(context, ConnectionService::class.java)
                    if (robot != null) {
                        try {
                            context.startForegroundService(intent.putExtra(EXTRA_ROBOT, robot))
                            started = true
                        } catch (e: RuntimeException) {
                            // The app is in the background (a reconnect finished there): no service, same connection.
                        }
                    } else if (started) {
                        context.stopService(intent)
                        started = false
                    }
                }
            }
        }
    }
}
