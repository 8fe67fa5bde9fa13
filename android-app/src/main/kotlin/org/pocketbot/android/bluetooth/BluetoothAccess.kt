package org.pocketbot.android.bluetooth

import android.Manifest
import android.bluetooth.BluetoothAdapter
import android.bluetooth.BluetoothManager
import android.content.BroadcastReceiver
import android.content.Context
import android.content.Intent
import android.content.IntentFilter
import android.content.pm.PackageManager
import android.os.Build
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import org.pocketbot.android.model.BluetoothPort
import org.pocketbot.android.model.BluetoothStatus
import org.pocketbot.sdk.transport.Discoverer
import org.pocketbot.sdk.transport.RobotDevice

/**
 * The phone's Bluetooth as the app sees it: whether it exists, whether the user granted the permissions it needs,
 * whether it is on; kept current by the adapter's state broadcasts and by [refresh] (after a permission answer).
 */
public class BluetoothAccess(private val context: Context) : BluetoothPort {
    private val adapter: BluetoothAdapter? = context.getSystemService(BluetoothManager::class.java)?.adapter
    private val _status = MutableStateFlow(BluetoothStatus.READY)
    private var refused = false
    private var blocked = false

    override val status: StateFlow<BluetoothStatus> = _status.asStateFlow()

    init {
        refresh()
        if (adapter != null) {
            val receiver = object : BroadcastReceiver() {
                override fun onReceive(context: Context, intent: Intent) = refresh()
            }
            context.registerReceiver(receiver, IntentFilter(BluetoothAdapter.ACTION_STATE_CHANGED), Context.RECEIVER_EXPORTED)
        }
    }

    /** The runtime permissions Bluetooth needs on this Android version. */
    public val permissions: Array<String>
        get() = if (Build.VERSION.SDK_INT >= Build.VERSION_CODES.S) {
            arrayOf(Manifest.permission.BLUETOOTH_SCAN, Manifest.permission.BLUETOOTH_CONNECT)
        } else {
            arrayOf(Manifest.permission.ACCESS_FINE_LOCATION)
        }

    /**
     * Called with the user's answer to the permission request; [canAskAgain] is whether Android would show its dialog
     * again (after a second "Don't allow" it does not, and a request is refused without asking).
     */
    public fun permissionsAnswered(canAskAgain: Boolean) {
        refused = !granted()
        blocked = refused && !canAskAgain
        refresh()
    }

    override fun refresh() {
        _status.value = when {
            adapter == null -> BluetoothStatus.UNAVAILABLE
            !granted() -> when {
                blocked -> BluetoothStatus.PERMISSION_BLOCKED
                refused -> BluetoothStatus.PERMISSION_REFUSED
                else -> BluetoothStatus.PERMISSION_NEEDED
            }
            !adapter.isEnabled -> BluetoothStatus.OFF
            else -> BluetoothStatus.READY
        }
    }

    override fun discoverer(everyDevice: Boolean): Discoverer? =
        adapter?.takeIf { _status.value == BluetoothStatus.READY }?.let { AndroidBluetoothDiscoverer(context, it, everyDevice) }

    override fun deviceAt(address: String): RobotDevice? {
        val adapter = adapter?.takeIf { _status.value == BluetoothStatus.READY && BluetoothAdapter.checkBluetoothAddress(address) } ?: return null
        val device = adapter.getRemoteDevice(address)
        val name = try {
            device.name
        } catch (e: SecurityException) {
            null
        }
        return BluetoothRobotDevice(device, name ?: address, adapter)
    }

    private fun granted(): Boolean = permissions.all { context.checkSelfPermission(it) == PackageManager.PERMISSION_GRANTED }
}
