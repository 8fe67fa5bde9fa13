package org.pocketbot.android.bluetooth

import android.bluetooth.BluetoothAdapter
import android.bluetooth.BluetoothDevice
import android.bluetooth.BluetoothSocket
import java.io.IOException
import java.util.UUID
import kotlin.coroutines.CoroutineContext
import kotlinx.coroutines.CancellationException
import kotlinx.coroutines.Dispatchers
import kotlinx.coroutines.async
import kotlinx.coroutines.coroutineScope
import kotlinx.coroutines.runInterruptible
import kotlinx.coroutines.flow.MutableStateFlow
import kotlinx.coroutines.flow.StateFlow
import kotlinx.coroutines.flow.asStateFlow
import kotlinx.coroutines.withContext
import org.pocketbot.android.model.DescribedLink
import org.pocketbot.android.model.LinkKind
import org.pocketbot.sdk.transport.ByteStream
import org.pocketbot.sdk.transport.RobotDevice
import org.pocketbot.sdk.transport.SlipStreamTransport
import org.pocketbot.sdk.transport.Transport
import org.pocketbot.sdk.transport.TransportLostException

/**
 * A [Transport] over Bluetooth Classic RFCOMM, the Serial Port Profile a PocketBot2's Bluetooth module speaks: SLIP
 * frames on the socket's byte stream, as [SlipStreamTransport] does them for every stream link. Blocking socket
 * calls run on [Dispatchers.IO]; closing the transport closes the socket, which ends a read that waits.
 *
 * Needs the BLUETOOTH_CONNECT permission on Android 12 and later (BLUETOOTH before).
 */
public class AndroidBluetoothTransport private constructor(
    address: String,
    stream: ByteStream,
    context: CoroutineContext,
) : SlipStreamTransport(address, stream, context) {
    public companion object {
        /** The Serial Port Profile's service UUID: the RFCOMM channel a robot's Bluetooth module serves. */
        public val SPP_UUID: UUID = UUID.fromString("00001101-0000-1000-8000-00805F9B34FB")

        /**
         * Opens an RFCOMM socket to [device]'s Serial Port Profile and returns the transport once connected. A secure
         * socket first (authenticated and encrypted: pairing); where the robot's module refuses it, an insecure one
         * ([insecureFirst] tries that first, for a robot known to need it). [linkOpened] is told which one is used.
         * Cancelling the caller closes the socket being connected. Throws [TransportLostException] when the robot
         * cannot be reached (off, out of range, not paired and the user declined, Bluetooth switched off).
         */
        public suspend fun connect(
            device: BluetoothDevice,
            adapter: BluetoothAdapter?,
            insecureFirst: Boolean = false,
            linkOpened: (secure: Boolean) -> Unit = {},
            context: CoroutineContext = Dispatchers.Default,
        ): AndroidBluetoothTransport {
            val address = bluetoothAddress(device.address)
            // Android refuses RFCOMM sockets while the adapter is off, with an IOException that says nothing.
            if (adapter?.isEnabled == false) throw TransportLostException("$address: Bluetooth is off")
            val failures = ArrayList<String>()
            for (secure in if (insecureFirst) listOf(false, true) else listOf(true, false)) {
                val socket = try {
                    open(device, adapter, secure)
                } catch (e: IOException) {
                    failures += "${kind(secure)}: no socket: ${e.message}"
                    continue
                }
                val failed = connect(socket)
                if (failed == null) {
                    linkOpened(secure)
                    return AndroidBluetoothTransport(address, SocketStream(socket), context)
                }
                failures += "${kind(secure)}: $failed"
            }
            throw TransportLostException("$address: cannot connect (${failures.joinToString("; ")})")
        }

        private fun kind(secure: Boolean) = if (secure) "secure RFCOMM" else "insecure RFCOMM"

        private fun open(device: BluetoothDevice, adapter: BluetoothAdapter?, secure: Boolean): BluetoothSocket = try {
            // A running discovery slows a connection down a lot; it is over for this robot anyway.
            adapter?.cancelDiscovery()
            if (secure) device.createRfcommSocketToServiceRecord(SPP_UUID) else device.createInsecureRfcommSocketToServiceRecord(SPP_UUID)
        } catch (e: SecurityException) {
            throw TransportLostException("${bluetoothAddress(device.address)}: Bluetooth permission missing: ${e.message}", e)
        }

        /** Connects [socket]: null once connected, else why not (the socket is closed then). */
        private suspend fun connect(socket: BluetoothSocket): String? = try {
            coroutineScope {
                // connect() blocks and cannot be interrupted: a cancelled caller closes the socket to end it.
                val connecting = async(Dispatchers.IO) { socket.connect() }
                try {
                    connecting.await()
                } catch (e: CancellationException) {
                    socket.close()
                    throw e
                }
            }
            null
        } catch (e: IOException) {
            socket.close()
            e.message ?: "no answer"
        }

        /** How a Bluetooth robot's address reads in [Transport.address]. */
        public fun bluetoothAddress(mac: String): String = "bluetooth:$mac"
    }
}

/**
 * A robot found over Bluetooth; [open] connects a new RFCOMM socket each time, insecure first once the robot refused
 * a secure one, and [linkKind] says which is in use.
 */
public class BluetoothRobotDevice(
    public val device: BluetoothDevice,
    override val name: String,
    private val adapter: BluetoothAdapter?,
) : RobotDevice, DescribedLink {
    override val address: String = AndroidBluetoothTransport.bluetoothAddress(device.address)
    private val _linkKind = MutableStateFlow<LinkKind?>(null)
    override val linkKind: StateFlow<LinkKind?> = _linkKind.asStateFlow()

    override suspend fun open(): Transport =
        AndroidBluetoothTransport.connect(device, adapter, insecureFirst = _linkKind.value?.warning == true, linkOpened = { secure ->
            _linkKind.value = if (secure) SECURE else INSECURE
        })

    private companion object {
        val SECURE = LinkKind("secure RFCOMM (paired, encrypted)")
        val INSECURE = LinkKind("insecure RFCOMM (not encrypted: the robot refused a secure link)", warning = true)
    }

    override fun toString(): String = "$name ($address)"
    override fun equals(other: Any?): Boolean = other is BluetoothRobotDevice && other.device.address == device.address
    override fun hashCode(): Int = device.address.hashCode()
}

/** An RFCOMM socket's streams as a [ByteStream]. */
private class SocketStream(private val socket: BluetoothSocket) : ByteStream {
    private val input = socket.inputStream
    private val output = socket.outputStream

    override suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int =
        runInterruptible(Dispatchers.IO) { input.read(buffer, offset, length) }

    override suspend fun write(bytes: ByteArray) = withContext(Dispatchers.IO) {
        output.write(bytes)
        output.flush()
    }

    override fun close() {
        try {
            socket.close()
        } catch (e: IOException) {
            // Closing a socket whose link already broke may fail; it is closed either way.
        }
    }
}
