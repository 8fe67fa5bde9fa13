package org.pocketbot.sdk.transport

/**
 * Robot addresses as people type them and as [RobotDevice.address] writes them for robots that need no scan:
 * `tcp://HOST:PORT` (an emulated robot, a serial-to-TCP bridge; an IPv6 host in brackets, `tcp://[::1]:7000`) and
 * `serial:PATH` (`serial:/dev/rfcomm0`, `serial:/dev/ttyUSB0`, `serial:COM3`).
 *
 * ```
 * val robot = RobotAddress.parse("tcp://127.0.0.1:7000").connect(this)
 * ```
 */
public object RobotAddress {
    private val TCP = Regex("""tcp://(\[[0-9A-Fa-f:.]+]|[^:/\[\]]+)(?::([^/]*))?/?""")
    private const val FORMS = "tcp://HOST:PORT (e.g. tcp://127.0.0.1:7000) or serial:PATH (e.g. serial:/dev/rfcomm0)"

    /**
     * The robot at [address], not connected yet (connecting is [RobotDevice.connect]'s work).
     *
     * @throws IllegalArgumentException saying what is wrong and how such an address is written: no port, a port
     *   that is no number or not in 1..65535, an empty path, a kind of address other than `tcp://` and `serial:`
     *   (Bluetooth robots are found by [BluezDiscoverer]).
     */
    public fun parse(address: String): RobotDevice {
        val text = address.trim()
        require(text.isNotEmpty()) { "empty robot address: write $FORMS" }
        return when {
            text.startsWith("tcp:", ignoreCase = true) -> parseTcp(text)
            text.startsWith("serial:", ignoreCase = true) -> {
                val path = text.substring("serial:".length)
                require(path.isNotBlank()) { "'$text' names no port: write serial:PATH, e.g. serial:/dev/rfcomm0" }
                SerialRobotDevice(path)
            }
            text.startsWith("bluetooth:", ignoreCase = true) ->
                throw IllegalArgumentException("'$text': Bluetooth robots are found by a scan (BluezDiscoverer), or reached by their RFCOMM port: serial:/dev/rfcomm0")
            else -> throw IllegalArgumentException("'$text' is no robot address: write $FORMS")
        }
    }

    /**
     * Whether [text] is meant as an address [parse] reads (it starts with `tcp:` or `serial:`), right or wrong,
     * rather than a robot's name or id: a command line that takes either parses those with [parse] (and reports its
     * error) and looks the others up among the robots it found.
     */
    public fun isAddress(text: String): Boolean = text.trim().let { it.startsWith("tcp:", ignoreCase = true) || it.startsWith("serial:", ignoreCase = true) }

    private fun parseTcp(text: String): RobotDevice {
        val m = TCP.matchEntire(text)
            ?: throw IllegalArgumentException("'$text' is no TCP address: write tcp://HOST:PORT, e.g. tcp://127.0.0.1:7000 (an IPv6 host in brackets)")
        val host = m.groupValues[1].removePrefix("[").removeSuffix("]")
        val portText = m.groups[2]?.value
        require(!portText.isNullOrEmpty()) { "'$text' has no port: write tcp://$host:PORT, e.g. tcp://$host:7000" }
        val port = portText.toIntOrNull()
        require(port != null && port in 1..65535) { "'$portText' in '$text' is not a TCP port (1..65535)" }
        return TcpRobotDevice(host, port)
    }
}
