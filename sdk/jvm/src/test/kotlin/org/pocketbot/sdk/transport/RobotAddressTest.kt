package org.pocketbot.sdk.transport

import kotlin.test.Test
import kotlin.test.assertEquals
import kotlin.test.assertFailsWith
import kotlin.test.assertFalse
import kotlin.test.assertIs
import kotlin.test.assertTrue

class RobotAddressTest {
    @Test
    fun tcpAndSerialAddressesGiveTheirDevicesAndReadBackTheSame() {
        val tcp = assertIs<TcpRobotDevice>(RobotAddress.parse("tcp://127.0.0.1:7000"))
        assertEquals("127.0.0.1" to 7000, tcp.host to tcp.port)
        assertEquals("tcp://127.0.0.1:7000", tcp.address)
        val v6 = assertIs<TcpRobotDevice>(RobotAddress.parse("tcp://[::1]:40001"))
        assertEquals("::1", v6.host)
        assertEquals("tcp://[::1]:40001", v6.address)
        assertEquals("tcp://robots.lab:1", RobotAddress.parse(" tcp://robots.lab:1 ").address)
        val serial = assertIs<SerialRobotDevice>(RobotAddress.parse("serial:/dev/rfcomm0"))
        assertEquals("/dev/rfcomm0", serial.path)
        assertEquals("serial:/dev/rfcomm0", serial.address)
        assertEquals("COM3", assertIs<SerialRobotDevice>(RobotAddress.parse("serial:COM3")).path)
    }

    @Test
    fun badAddressesSayWhatIsWrongAndHowToWriteThem() {
        fun error(text: String) = assertFailsWith<IllegalArgumentException> { RobotAddress.parse(text) }.message!!
        assertEquals("'tcp://localhost' has no port: write tcp://localhost:PORT, e.g. tcp://localhost:7000", error("tcp://localhost"))
        assertEquals("'tcp://localhost:' has no port: write tcp://localhost:PORT, e.g. tcp://localhost:7000", error("tcp://localhost:"))
        assertEquals("'0' in 'tcp://h:0' is not a TCP port (1..65535)", error("tcp://h:0"))
        assertEquals("'65536' in 'tcp://h:65536' is not a TCP port (1..65535)", error("tcp://h:65536"))
        assertEquals("'x' in 'tcp://h:x' is not a TCP port (1..65535)", error("tcp://h:x"))
        assertTrue(error("tcp:h:1").startsWith("'tcp:h:1' is no TCP address: write tcp://HOST:PORT"))
        assertTrue(error("tcp://:7000").startsWith("'tcp://:7000' is no TCP address"))
        assertEquals("'serial:' names no port: write serial:PATH, e.g. serial:/dev/rfcomm0", error("serial:"))
        assertTrue(error("bluetooth:AA:BB:CC:DD:EE:FF").contains("found by a scan"))
        assertTrue(error("ftp://x").startsWith("'ftp://x' is no robot address: write tcp://HOST:PORT"))
        assertTrue(error("").startsWith("empty robot address"))
    }

    @Test
    fun onlyTcpAndSerialTextsAreTakenForAddresses() {
        assertTrue(RobotAddress.isAddress("tcp://127.0.0.1"))
        assertTrue(RobotAddress.isAddress("serial:/dev/ttyUSB0"))
        assertFalse(RobotAddress.isAddress("PocketBot-1"))
        assertFalse(RobotAddress.isAddress("3"))
        assertFalse(RobotAddress.isAddress("bluetooth:AA:BB:CC:DD:EE:FF"))
    }
}
