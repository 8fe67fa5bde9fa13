package org.pocketbot.sdk.transport

import kotlin.time.Duration
import kotlin.time.Duration.Companion.seconds
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.channels.Channel
import kotlinx.coroutines.flow.Flow
import kotlinx.coroutines.flow.channelFlow
import kotlinx.coroutines.flow.flowOn
import kotlinx.coroutines.runInterruptible
import kotlinx.coroutines.withTimeoutOrNull
import org.freedesktop.dbus.annotations.DBusInterfaceName
import org.freedesktop.dbus.connections.impl.DBusConnection
import org.freedesktop.dbus.connections.impl.DBusConnectionBuilder
import org.freedesktop.dbus.exceptions.DBusException
import org.freedesktop.dbus.exceptions.DBusExecutionException
import org.freedesktop.dbus.interfaces.DBusInterface
import org.freedesktop.dbus.interfaces.ObjectManager
import org.freedesktop.dbus.interfaces.Properties
import org.freedesktop.dbus.types.Variant
import java.io.File

/**
 * Finds PocketBots with Linux's Bluetooth stack, BlueZ, over D-Bus: starts discovery on an adapter
 * (`org.bluez.Adapter1.StartDiscovery`), reports the robots BlueZ already knows (`GetManagedObjects`: paired
 * ones and those seen recently) and those it finds while searching (`InterfacesAdded`, and `PropertiesChanged`
 * when a device's name or services arrive late), then stops discovery after [duration]. A device is a robot when
 * [isRobot] says so: by default, its name starts with `PocketBot` or it offers the Serial Port Profile
 * ([SPP_UUID]).
 *
 * **Connecting.** The robots talk SPP (RFCOMM, a serial stream). On Linux the plain way to reach an RFCOMM
 * channel from the JVM is a tty bound to the robot's address, once, by the user:
 * ```
 * sudo rfcomm bind 0 00:11:22:33:44:55 1     # creates /dev/rfcomm0 for channel 1 of that robot
 * ```
 * (pair first, e.g. with `bluetoothctl`). The kernel connects when the tty is opened and disconnects when it is
 * closed. [ttyFor] maps a robot's Bluetooth address to its tty; by default [RfcommTtys.bound] reads the bindings
 * the kernel lists in `/sys/class/tty/rfcommN/address`, so a bound robot needs no configuration. The mapping is
 * asked when the device is opened, so binding after discovery works. A robot without a tty is still reported;
 * opening it throws a [TransportLostException] that says how to bind one.
 *
 * ```
 * val devices = BluezDiscoverer(duration = 8.seconds).discover().toList()
 * val transport = devices.first().open()        // SerialTransport on /dev/rfcommN
 * ```
 *
 * [discover] runs its D-Bus calls on [Dispatchers.IO] and may be collected from any coroutine; cancelling the
 * collection stops discovery. It throws [TransportLostException] when the bus, BlueZ or the adapter is missing (at once
 * when Linux lists no such adapter in `/sys/class/bluetooth`).
 *
 * @param adapter the adapter's name as BlueZ calls it (`hci0`).
 * @param duration how long to search; [Duration.INFINITE] searches until the collector cancels.
 * @param busAddress a D-Bus address to use instead of the system bus (tests use a private bus).
 * @param baud the baud rate the serial transport is opened with (RFCOMM ttys ignore it).
 * @param ttyFor the RFCOMM tty bound to a Bluetooth address (`00:11:22:33:44:55`, upper case), or null.
 * @param isRobot which devices are robots.
 */
public class BluezDiscoverer(
    public val adapter: String = "hci0",
    public val duration: Duration = 10.seconds,
    private val busAddress: String? = null,
    private val baud: Int = SerialTransport.DEFAULT_BAUD,
    private val ttyFor: (bluetoothAddress: String) -> String? = { RfcommTtys.bound()[it] },
    private val isRobot: (BluetoothDeviceInfo) -> Boolean = ::looksLikePocketBot,
) : Discoverer {
    private val adapterPath = "/org/bluez/$adapter"

    override fun discover(): Flow<RobotDevice> = channelFlow {
        // Linux lists its Bluetooth adapters in sysfs: without one, D-Bus need not be asked (it takes seconds to say no).
        if (busAddress == null && File("/sys/class").isDirectory && !File("/sys/class/bluetooth/$adapter").exists()) {
            throw TransportLostException("no Bluetooth adapter $adapter on this machine")
        }
        val events = Channel<Pair<String, Map<String, Variant<*>>>>(Channel.UNLIMITED)
        val connection = connect()
        try {
            val handlers = listOf(
                connection.addSigHandler(ObjectManager.InterfacesAdded::class.java) { signal ->
                    // dbus-java names them oddly: signalSource is the added object, objectPath the manager
                    signal.interfaces[DEVICE_INTERFACE]?.let { events.trySend(signal.signalSource.path to it) }
                },
                connection.addSigHandler(Properties.PropertiesChanged::class.java) { signal ->
                    if (signal.interfaceName == DEVICE_INTERFACE) events.trySend(signal.path to signal.propertiesChanged)
                },
            )
            val adapterObject = connection.getRemoteObject(BLUEZ, adapterPath, Adapter1::class.java)
            try {
                call("start discovery on $adapter") {
                    // PocketBot2 speaks SPP, i.e. classic Bluetooth: skip the Low Energy inquiry. An old BlueZ
                    // without discovery filters searches everything, which only costs time.
                    runCatching { adapterObject.SetDiscoveryFilter(mapOf("Transport" to Variant("bredr"))) }
                    try {
                        adapterObject.StartDiscovery()
                    } catch (e: DBusExecutionException) {
                        // another program is already searching on this adapter: its results are ours too
                        @Suppress("DEPRECATION")
                        if (e.type != "org.bluez.Error.InProgress") throw e
                    }
                }
                val known = call("list BlueZ's devices") {
                    connection.getRemoteObject(BLUEZ, "/", ObjectManager::class.java).GetManagedObjects()
                }
                for ((path, interfaces) in known) interfaces[DEVICE_INTERFACE]?.let { events.trySend(path.path to it) }

                val devices = HashMap<String, MutableMap<String, Variant<*>>>()
                val reported = HashSet<String>()
                withTimeoutOrNull(duration) {
                    for ((path, properties) in events) {
                        if (!path.startsWith("$adapterPath/")) continue
                        val all = devices.getOrPut(path) { HashMap() }.apply { putAll(properties) }
                        val info = info(path, all) ?: continue
                        if (path !in reported && isRobot(info)) {
                            reported += path
                            send(BluetoothRobotDevice(info.name ?: info.address, info.address, baud, ttyFor))
                        }
                    }
                }
            } finally {
                runCatching { adapterObject.StopDiscovery() }
                handlers.forEach { runCatching { it.close() } }
            }
        } finally {
            events.close()
            runCatching { connection.close() }
        }
    }.flowOn(Dispatchers.IO)

    private suspend fun connect(): DBusConnection = call("connect to ${busAddress ?: "the system bus (is D-Bus running, with BlueZ?)"}") {
        val builder = if (busAddress != null) DBusConnectionBuilder.forAddress(busAddress)
        else DBusConnectionBuilder.forSystemBus()
        builder.withShared(false).build()
    }

    private suspend fun <T> call(what: String, block: () -> T): T = runInterruptible(Dispatchers.IO) {
        try {
            block()
        } catch (e: DBusException) {
            throw TransportLostException("bluetooth $adapter: cannot $what: ${reason(e)}", e)
        } catch (e: DBusExecutionException) {
            throw TransportLostException("bluetooth $adapter: cannot $what: ${reason(e)}", e)
        }
    }

    /** dbus-java appends its cause's message even when there is none ("Failed to connect to bus: null"). */
    private fun reason(e: Exception): String = e.message?.removeSuffix(": null") ?: e::class.simpleName ?: "unknown error"

    override fun toString(): String = "BluezDiscoverer($adapter)"

    public companion object {
        /** The Serial Port Profile's service class UUID, which PocketBot2's Bluetooth module offers. */
        public const val SPP_UUID: String = "00001101-0000-1000-8000-00805f9b34fb"

        /** The name prefix of PocketBot robots (`PocketBot-3`). */
        public const val NAME_PREFIX: String = "PocketBot"

        /** The default robot filter: a name starting with [NAME_PREFIX], or the [SPP_UUID] among the services. */
        public fun looksLikePocketBot(device: BluetoothDeviceInfo): Boolean =
            device.name?.startsWith(NAME_PREFIX) == true || device.uuids.any { it.equals(SPP_UUID, ignoreCase = true) }

        private const val BLUEZ = "org.bluez"
        private const val DEVICE_INTERFACE = "org.bluez.Device1"

        private fun info(path: String, p: Map<String, Variant<*>>): BluetoothDeviceInfo? {
            val address = p["Address"]?.value as? String ?: return null
            val name = (p["Name"]?.value ?: p["Alias"]?.value) as? String
            val uuids = when (val v = p["UUIDs"]?.value) {
                is Collection<*> -> v.filterIsInstance<String>()
                is Array<*> -> v.filterIsInstance<String>()
                else -> emptyList()
            }
            return BluetoothDeviceInfo(
                objectPath = path,
                address = address.uppercase(),
                name = name,
                uuids = uuids,
                paired = p["Paired"]?.value as? Boolean ?: false,
                rssi = (p["RSSI"]?.value as? Number)?.toInt(),
            )
        }
    }
}

/**
 * What BlueZ knows about a Bluetooth device (its `org.bluez.Device1` properties), as [BluezDiscoverer]'s filter
 * sees it.
 *
 * @property objectPath the device's D-Bus object, `/org/bluez/hci0/dev_00_11_22_33_44_55`.
 * @property address the Bluetooth address, upper case, `00:11:22:33:44:55`.
 * @property name the advertised name (or BlueZ's alias for it), null while unknown.
 * @property uuids the service class UUIDs the device offers, lower case as BlueZ reports them.
 * @property paired whether the device is paired with this adapter.
 * @property rssi the received signal strength of the latest inquiry result, in dBm, or null.
 */
public class BluetoothDeviceInfo internal constructor(
    public val objectPath: String,
    public val address: String,
    public val name: String?,
    public val uuids: List<String>,
    public val paired: Boolean,
    public val rssi: Int?,
) {
    // Not a data class: a property BlueZ offers later can be added without breaking callers (no componentN, no copy).
    override fun equals(other: Any?): Boolean = other is BluetoothDeviceInfo && objectPath == other.objectPath &&
        address == other.address && name == other.name && uuids == other.uuids && paired == other.paired && rssi == other.rssi

    override fun hashCode(): Int = listOf(objectPath, address, name, uuids, paired, rssi).hashCode()

    override fun toString(): String = "BluetoothDeviceInfo($address, name=$name, paired=$paired, rssi=$rssi, $objectPath)"
}

/**
 * A robot found over Bluetooth (see [BluezDiscoverer]); [open] connects through the RFCOMM tty bound to its
 * address, as a [SerialTransport].
 *
 * @property bluetoothAddress the robot's Bluetooth address, `00:11:22:33:44:55`.
 */
public class BluetoothRobotDevice internal constructor(
    override val name: String,
    public val bluetoothAddress: String,
    private val baud: Int,
    private val ttyFor: (String) -> String?,
) : RobotDevice {
    /** `bluetooth:00:11:22:33:44:55`; the open transport's address is its tty's (`serial:/dev/rfcomm0`). */
    override val address: String = "bluetooth:$bluetoothAddress"

    /**
     * Opens the RFCOMM tty bound to the robot; throws [TransportLostException] when none is bound, or when the
     * robot does not answer (the kernel connects when the tty opens). Safe from any coroutine.
     */
    override suspend fun open(): Transport {
        val tty = ttyFor(bluetoothAddress) ?: throw TransportLostException(
            "$address ($name): no RFCOMM tty is bound to this robot; bind one with " +
                "`sudo rfcomm bind 0 $bluetoothAddress 1` (it becomes /dev/rfcomm0), or pass ttyFor to BluezDiscoverer")
        return SerialTransport.open(tty, baud)
    }

    override fun toString(): String = "$name ($address)"
}

/** BlueZ's adapter interface; only what discovery needs. */
@DBusInterfaceName("org.bluez.Adapter1")
internal interface Adapter1 : DBusInterface {
    @Suppress("FunctionName") fun SetDiscoveryFilter(filter: Map<String, Variant<*>>)
    @Suppress("FunctionName") fun StartDiscovery()
    @Suppress("FunctionName") fun StopDiscovery()
}
