package org.pocketbot.android

import android.app.Application
import kotlinx.coroutines.CoroutineScope
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.SupervisorJob
import org.pocketbot.android.bluetooth.BluetoothAccess
import org.pocketbot.android.model.AppModel
import org.pocketbot.sdk.transport.EmulatorDiscoverer

/** What the Activity and the service get from the Application: the process-wide model, the phone's Bluetooth, the service. */
interface ModelOwner {
    val model: AppModel
    val bluetoothAccess: BluetoothAccess
    val connectionService: ConnectionService.Keeper
}

/**
 * The app's process: it owns the [AppModel], so a connected robot outlives Activities (rotation, background), and
 * keeps [ConnectionService] running while a robot is connected, so Android keeps the process while the app is not
 * on screen.
 */
class PocketBotApp : Application(), ModelOwner {
    override lateinit var model: AppModel
        private set
    override lateinit var bluetoothAccess: BluetoothAccess
        private set
    override lateinit var connectionService: ConnectionService.Keeper
        private set

    override fun onCreate() {
        super.onCreate()
        bluetoothAccess = BluetoothAccess(this)
        // The main thread for the model; the robots' own work runs on Dispatchers.Default (the SDK's choice).
        val scope = CoroutineScope(SupervisorJob() + Dispatchers.Main.immediate)
        model = AppModel(scope, bluetoothAccess, emulatorAt = { host, port -> EmulatorDiscoverer(host, port) })
        connectionService = ConnectionService.Keeper(this, model)
    }
}
