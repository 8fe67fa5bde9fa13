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
import kotlinx.coroutines.withContext
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
         * Opens an RFCOMM socket to [device]'s Serial Port Profile and returns the transport once connected. Cancelling
         * the caller closes the socket being connected. Throws [TransportLostException] when the robot cannot be reached
         * (off, out of range, not paired and the user declined, Bluetooth switched off).
         */
        public suspend fun connect(device: BluetoothDevice, adapter: BluetoothAdapter?, context: CoroutineContext = Dispatchers.Default): AndroidBluetoothTransport {
            val address = bluetoothAddress(device.address)
            // Android refuses RFCOMM sockets while the adapter is off, with an IOException that says nothing.
            if (adapter?.isEnabled == false) throw TransportLostException("$address: Bluetooth is off")
            val socket = try {
                // A running discovery slows a connection down a lot; it is over for this robot anyway.
                adapter?.cancelDiscovery()
                device.createRfcommSocketToServiceRecord(SPP_UUID)
            } catch (e: IOException) {
                throw TransportLostException("$address: no RFCOMM socket: ${e.message}", e)
            } catch (e: SecurityException) {
                throw TransportLostException("$address: Bluetooth permission missing: ${e.message}", e)
            }
            try {
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
            } catch (e: IOException) {
                socket.close()
                throw TransportLostException("$address: cannot connect: ${e.message ?: "no answer"}", e)
            }
            return AndroidBluetoothTransport(address, SocketStream(socket), context)
        }

        /** How a Bluetooth robot's address reads in [Transport.address]. */
        public fun bluetoothAddress(mac: String): String = "bluetooth:$mac"
    }
}

/** A robot found over Bluetooth; [open] connects a new RFCOMM socket each time. */
public class BluetoothRobotDevice(
    public val device: BluetoothDevice,
    override val name: String,
    private val adapter: BluetoothAdapter?,
) : RobotDevice {
    override val address: String = AndroidBluetoothTransport.bluetoothAddress(device.address)

    override suspend fun open(): Transport = AndroidBluetoothTransport.connect(device, adapter)

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
