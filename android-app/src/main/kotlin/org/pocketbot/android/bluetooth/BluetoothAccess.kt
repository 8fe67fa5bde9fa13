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

/**
 * The phone's Bluetooth as the app sees it: whether it exists, whether the user granted the permissions it needs,
 * whether it is on; kept current by the adapter's state broadcasts and by [refresh] (after a permission answer).
 */
public class BluetoothAccess(private val context: Context) : BluetoothPort {
    private val adapter: BluetoothAdapter? = context.getSystemService(BluetoothManager::class.java)?.adapter
    private val _status = MutableStateFlow(BluetoothStatus.READY)
    private var refusedOnce = false

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

    /** Called with the user's answer to the permission request. */
    public fun permissionsAnswered() {
        refusedOnce = !granted()
        refresh()
    }

    override fun refresh() {
        _status.value = when {
            adapter == null -> BluetoothStatus.UNAVAILABLE
            !granted() -> if (refusedOnce) BluetoothStatus.PERMISSION_REFUSED else BluetoothStatus.PERMISSION_NEEDED
            !adapter.isEnabled -> BluetoothStatus.OFF
            else -> BluetoothStatus.READY
        }
    }

    override fun discoverer(): Discoverer? =
        adapter?.takeIf { _status.value == BluetoothStatus.READY }?.let { AndroidBluetoothDiscoverer(context, it) }

    private fun granted(): Boolean = permissions.all { context.checkSelfPermission(it) == PackageManager.PERMISSION_GRANTED }
}
