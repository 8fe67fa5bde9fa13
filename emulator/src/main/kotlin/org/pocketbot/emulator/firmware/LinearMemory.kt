package org.pocketbot.emulator.firmware

import com.dylibso.chicory.runtime.ByteArrayMemory
import com.dylibso.chicory.runtime.Instance
import com.dylibso.chicory.runtime.Memory
import com.dylibso.chicory.runtime.TrapException
import com.dylibso.chicory.runtime.WasmRuntimeException
import com.dylibso.chicory.wasm.types.DataSegment
import com.dylibso.chicory.wasm.types.MemoryLimits
import com.dylibso.chicory.wasm.types.PassiveDataSegment
import java.lang.invoke.MethodHandles
import java.lang.invoke.VarHandle
import java.nio.ByteOrder

/**
 * A WebAssembly linear memory (not shared) held in one byte array, [bytes], that [ChicoryEngine] points at the
 * memory of the robot whose firmware it runs. One array instead of Chicory's array of 64 KiB pages: an access is one
 * bounds check and one load, and the memory's state is just the array (plus the data segments, which the engine
 * only shares between robots when the code never drops one).
 */
internal class LinearMemory(private val limits: MemoryLimits) : Memory, FirmwareMemory {
    init {
        require(!limits.shared()) { "shared memories are not supported" }
    }

    /** The memory's contents, pages() * 64 KiB long; replaced by [grow]. */
    @JvmField var bytes: ByteArray = ByteArray(limits.initialPages() * Memory.PAGE_SIZE)

    private var dataSegments: Array<DataSegment> = emptyArray()

    override val size: Int get() = bytes.size
    override fun pages(): Int = bytes.size ushr 16
    override fun initialPages(): Int = limits.initialPages()
    override fun maximumPages(): Int = minOf(limits.maximumPages(), Memory.RUNTIME_MAX_PAGES)
    override fun shared(): Boolean = false

    override fun grow(delta: Int): Int {
        val old = pages()
        val new = old.toLong() + delta
        if (delta < 0 || new > maximumPages()) return -1
        if (delta > 0) bytes = bytes.copyOf((new * Memory.PAGE_SIZE).toInt())
        return old
    }

    // Atomics on an unshared memory: the interface's defaults synchronise on lock(); nothing ever waits.
    override fun lock(address: Int): Any = this
    override fun waitOn(address: Int, expected: Int, timeout: Long): Int = throw TrapException("expected shared memory")
    override fun waitOn(address: Int, expected: Long, timeout: Long): Int = throw TrapException("expected shared memory")
    override fun notify(address: Int, maxThreads: Int): Int = 0

    /** Copies the active data segments in, with Chicory's own checks (it happens once per image). */
    override fun initialize(instance: Instance, segments: Array<DataSegment>?) {
        dataSegments = segments ?: emptyArray()
        val reference = ByteArrayMemory(MemoryLimits(pages(), maxOf(pages(), 1)))
        reference.initialize(instance, segments)
        bytes = reference.readBytes(0, bytes.size)
    }

    override fun initPassiveSegment(segment: Int, address: Int, offset: Int, size: Int) =
        write(address, dataSegments[segment].data(), offset, size)

    override fun drop(segment: Int) { dataSegments[segment] = PassiveDataSegment.EMPTY }

    override fun write(address: Int, data: ByteArray, offset: Int, size: Int) {
        checkRange(offset, size, data.size)
        checkRange(address, size, bytes.size)
        System.arraycopy(data, offset, bytes, address, size)
    }

    override fun write(address: Int, data: ByteArray) = write(address, data, 0, data.size)

    override fun readBytes(address: Int, size: Int): ByteArray {
        checkRange(address, size, bytes.size)
        return bytes.copyOfRange(address, address + size)
    }

    override fun copy(dest: Int, src: Int, size: Int) {
        checkRange(src, size, bytes.size)
        checkRange(dest, size, bytes.size)
        System.arraycopy(bytes, src, bytes, dest, size)
    }

    override fun fill(value: Byte, fromIndex: Int, toIndex: Int) {
        checkRange(fromIndex, toIndex - fromIndex, bytes.size)
        bytes.fill(value, fromIndex, toIndex)
    }

    override fun zero() = bytes.fill(0)

    // The accessors run for every load and store of the firmware: the array's own bounds check is the only one.
    override fun read(address: Int): Byte = try { bytes[address] } catch (e: IndexOutOfBoundsException) { throw oob(address, 1) }
    override fun writeByte(address: Int, value: Byte) { try { bytes[address] = value } catch (e: IndexOutOfBoundsException) { throw oob(address, 1) } }
    override fun readShort(address: Int): Short = try { SHORT.get(bytes, address) as Short } catch (e: IndexOutOfBoundsException) { throw oob(address, 2) }
    override fun readU16(address: Int): Long = readShort(address).toLong() and 0xFFFF
    override fun writeShort(address: Int, value: Short) { try { SHORT.set(bytes, address, value) } catch (e: IndexOutOfBoundsException) { throw oob(address, 2) } }
    override fun readInt(address: Int): Int = try { INT.get(bytes, address) as Int } catch (e: IndexOutOfBoundsException) { throw oob(address, 4) }
    override fun writeI32(address: Int, value: Int) { try { INT.set(bytes, address, value) } catch (e: IndexOutOfBoundsException) { throw oob(address, 4) } }
    override fun readLong(address: Int): Long = try { LONG.get(bytes, address) as Long } catch (e: IndexOutOfBoundsException) { throw oob(address, 8) }
    override fun writeLong(address: Int, value: Long) { try { LONG.set(bytes, address, value) } catch (e: IndexOutOfBoundsException) { throw oob(address, 8) } }
    override fun readFloat(address: Int): Float = java.lang.Float.intBitsToFloat(readInt(address))
    override fun readF32(address: Int): Long = readInt(address).toLong() and 0xFFFFFFFFL
    override fun writeF32(address: Int, value: Float) = writeI32(address, java.lang.Float.floatToRawIntBits(value))
    override fun readDouble(address: Int): Double = java.lang.Double.longBitsToDouble(readLong(address))
    override fun readF64(address: Int): Long = readLong(address)
    override fun writeF64(address: Int, value: Double) = writeLong(address, java.lang.Double.doubleToRawLongBits(value))

    private fun checkRange(address: Int, size: Int, limit: Int) {
        if (address < 0 || size < 0 || address > limit - size) throw oob(address, size)
    }

    private fun oob(address: Int, size: Int) =
        WasmRuntimeException("out of bounds memory access: attempted to access address: $address but limit is: ${bytes.size} and size: $size")

    private companion object {
        val SHORT: VarHandle = MethodHandles.byteArrayViewVarHandle(ShortArray::class.java, ByteOrder.LITTLE_ENDIAN)
        val INT: VarHandle = MethodHandles.byteArrayViewVarHandle(IntArray::class.java, ByteOrder.LITTLE_ENDIAN)
        val LONG: VarHandle = MethodHandles.byteArrayViewVarHandle(LongArray::class.java, ByteOrder.LITTLE_ENDIAN)
    }
}
