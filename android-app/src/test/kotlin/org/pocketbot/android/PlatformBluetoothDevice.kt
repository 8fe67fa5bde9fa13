package org.pocketbot.android

import android.bluetooth.BluetoothDevice
import org.robolectric.annotation.Implements

/**
 * Android's own BluetoothDevice, in place of Robolectric 4.17's shadow of it, for the tests that run below Android 16
 * without bridging Bluetooth ([BridgedBluetoothDevice] replaces that shadow too).
 *
 * Robolectric's ShadowBluetoothDevice declares methods taking and returning `BluetoothDevice.BluetoothAddress`, a class
 * of Android 16 (API 36) that no android-all up to API 35 holds. When BluetoothDevice is first initialised, Robolectric
 * lists the shadow's methods (to find its static initialiser), the JVM resolves every type in their signatures, and
 * fails: NoClassDefFoundError. On API 31-33 that happens as soon as the app asks for the BluetoothManager: the adapter
 * fetches its IBluetooth binder, which Robolectric makes as a java.lang.reflect.Proxy, and a Proxy loads every type in
 * IBluetooth's methods, BluetoothDevice among them. (On 34 and 35 the adapter no longer asks for that binder, so only
 * a test that makes a BluetoothDevice meets it.)
 */
@Implements(BluetoothDevice::class)
class PlatformBluetoothDevice
