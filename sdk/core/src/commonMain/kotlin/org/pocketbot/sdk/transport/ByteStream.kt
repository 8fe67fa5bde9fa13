package org.pocketbot.sdk.transport

/**
 * A two-way byte stream to one robot: a socket, a serial port, an RFCOMM tty. It knows nothing about frames;
 * [SlipStreamTransport] turns it into a frame [Transport].
 *
 * [read] is called by one coroutine at a time and [write] by one coroutine at a time (the two may run
 * concurrently with each other); [close] may be called from any thread, at any time, more than once.
 */
public interface ByteStream {
    /**
     * Suspends until at least one byte arrived, copies at most [length] bytes into [buffer] at [offset] and
     * returns how many it copied (at least 1), or -1 when the peer closed the stream. Throws when the stream
     * broke; after [close] it returns -1 or throws.
     */
    public suspend fun read(buffer: ByteArray, offset: Int, length: Int): Int

    /** Writes all of [bytes] and flushes them. Throws when the stream broke or was closed. */
    public suspend fun write(bytes: ByteArray)

    /** Closes the stream and releases what it holds; wakes a pending [read]. Idempotent. */
    public fun close()
}
