package org.pocketbot.sdk.internal.link

import org.pocketbot.protocol.Heartbeat
import org.pocketbot.protocol.SaveSettings
import org.pocketbot.sdk.CommandWindowFullException
import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertNotEquals
import kotlin.test.assertNull
import kotlin.test.assertSame
import kotlin.test.assertTrue

class CommandTableTest {
    @Test
    fun aFullWindowRefusesTheNewestInsteadOfSpinning() {
        val table = CommandTable(window = 32)
        val open = List(32) { table.open(SaveSettings) }
        assertEquals(32, open.map { it.seq }.toSet().size, "every waiting command has its own number")
        val e = assertFailsWith<CommandWindowFullException> { table.open(SaveSettings) }
        assertEquals(32, e.window)
        table.close(open[5])
        val next = table.open(SaveSettings) // room again once one is answered
        assertTrue(next.seq !in open.filter { it !== open[5] }.map { it.seq }, "numbers of waiting commands are never reused")
    }

    @Test
    fun numbersRunFrom1To255AndSkipTheOnesInUse() {
        val table = CommandTable(window = 32)
        val held = table.open(SaveSettings) // seq 1 stays open for a whole round
        var last = held.seq
        repeat(300) {
            val p = table.open(SaveSettings)
            assertNotEquals(0, p.seq)
            assertNotEquals(held.seq, p.seq, "a number in use is never handed out twice")
            assertTrue(p.seq in 1..255)
            last = p.seq
            table.close(p)
        }
        assertNotEquals(held.seq, last)
    }

    @Test
    fun anAnswerFindsItsCommandOnlyBySeqAndType() {
        val table = CommandTable()
        val p = table.open(SaveSettings)
        assertSame(p, table.find(p.seq, SaveSettings.TYPE))
        assertNull(table.find(p.seq, Heartbeat.TYPE))
        table.close(p)
        assertNull(table.find(p.seq, SaveSettings.TYPE), "a late answer to a finished command finds nothing")
    }
}
