package org.pocketbot.android.bluetooth

import android.bluetooth.BluetoothAdapter
import android.bluetooth.BluetoothDevice
import android.content.BroadcastReceiver
import android.content.Context
import android.content.Intent
import android.content.IntentFilter
import kotlinx.coroutines.channels.awaitClose
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.callbackFlow
import org.pocketbot.android.model.AppModel
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.TransportLostException

/**
 * Finds PocketBot robots over Bluetooth Classic: first the paired (bonded) devices whose name starts with
 * [AppModel.NAME_PREFIX], then those a device discovery finds nearby (about 12 s). A device found before its name is
 * known (Android resolves names later and says so with `ACTION_NAME_CHANGED`) is offered once the name arrives. With
 * [everyDevice], every device is offered, named by its address until its name is known, and again when it is. The
 * flow completes when the discovery is over; cancelling it cancels the discovery.
 *
 * Needs BLUETOOTH_SCAN and BLUETOOTH_CONNECT on Android 12 and later, location (and the install-time Bluetooth
 * permissions) before; throws [TransportLostException] when Bluetooth is off or a permission is missing.
 */
public class AndroidBluetoothDiscoverer(
    private val context: Context,
    private val adapter: BluetoothAdapter,
    private val everyDevice: Boolean = false,
) : Discoverer {
    override fun discover(): Flow<RobotDevice> = callbackFlow {
        if (!adapter.isEnabled) throw TransportLostException("Bluetooth is off")
        val offered = HashMap<String, String>() // address -> the name it was offered under
        fun offer(device: BluetoothDevice, name: String?) {
            val robot = BluetoothRobotDevice(device, name ?: device.address, adapter)
            val wanted = everyDevice || (name != null && with(AppModel) { robot.looksLikePocketBot() })
            if (wanted && offered[device.address] != robot.name) {
                offered[device.address] = robot.name
                trySend(robot)
            }
        }
        val receiver = object : BroadcastReceiver() {
            override fun onReceive(context: Context, intent: Intent) {
                when (intent.action) {
                    BluetoothDevice.ACTION_FOUND, BluetoothDevice.ACTION_NAME_CHANGED -> {
                        @Suppress("DEPRECATION") // the typed getParcelableExtra is API 33
                        val device = intent.getParcelableExtra<BluetoothDevice>(BluetoothDevice.EXTRA_DEVICE) ?: return
                        offer(device, intent.getStringExtra(BluetoothDevice.EXTRA_NAME) ?: nameOf(device))
                    }
                    BluetoothAdapter.ACTION_DISCOVERY_FINISHED -> channel.close()
                }
            }
        }
        try {
            for (device in adapter.bondedDevices.orEmpty()) offer(device, nameOf(device))
            val filter = IntentFilter().apply {
                addAction(BluetoothDevice.ACTION_FOUND)
                addAction(BluetoothDevice.ACTION_NAME_CHANGED)
                addAction(BluetoothAdapter.ACTION_DISCOVERY_FINISHED)
            }
            // System broadcasts: exported, as the Bluetooth service sends them.
            context.registerReceiver(receiver, filter, Context.RECEIVER_EXPORTED)
            adapter.cancelDiscovery()
            if (!adapter.startDiscovery()) channel.close() // the paired robots are all there is
        } catch (e: SecurityException) {
            throw TransportLostException("Bluetooth permission missing: ${e.message}", e)
        }
        awaitClose {
            try {
                context.unregisterReceiver(receiver)
                adapter.cancelDiscovery()
            } catch (e: RuntimeException) {
                // Not registered (permission refused before) or permission withdrawn meanwhile: nothing to undo.
            }
        }
    }

    private fun nameOf(device: BluetoothDevice): String? = try {
        device.name
    } catch (e: SecurityException) {
        null
    }
}
