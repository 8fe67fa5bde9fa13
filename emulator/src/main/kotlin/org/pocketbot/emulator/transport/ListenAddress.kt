package org.pocketbot.emulator.transport

import java.net.Inet4Address
import java.net.InetAddress
import java.net.NetworkInterface

/**
 * Where an emulator's TCP endpoints and control port listen, and where other machines reach them.
 *
 * The default is the loopback address: only programs on this machine can drive the robots. A phone on the same
 * Wi-Fi needs the emulator on the network: the wildcard address ([ANY], every address of this machine) or one
 * address of one interface.
 */
public object ListenAddress {
    /** Only this machine (127.0.0.1). */
    public val LOOPBACK: InetAddress = InetAddress.getLoopbackAddress()

    /** Every address of this machine (0.0.0.0): the robots are on the network. */
    public val ANY: InetAddress = InetAddress.getByAddress(ByteArray(4))

    /**
     * The address named by [text]: an IP address (`0.0.0.0`, `192.168.1.20`, `::`) or a host name of this machine.
     * Throws [IllegalArgumentException] when it names nothing.
     */
    public fun parse(text: String): InetAddress {
        require(text.isNotBlank()) { "an empty listen address" }
        return try {
            InetAddress.getByName(text.trim().removeSurrounding("[", "]"))
        } catch (e: java.net.UnknownHostException) {
            throw IllegalArgumentException("$text is no address of this machine: ${e.message}", e)
        }
    }

    /**
     * The addresses at which another program reaches an emulator listening on [listen], best first: [listen]
     * itself when it is one address; for the wildcard address, this machine's [networkAddresses], or the loopback
     * address when the machine has no network.
     */
    public fun reachable(listen: InetAddress): List<InetAddress> {
        if (!listen.isAnyLocalAddress) return listOf(listen)
        return networkAddresses().ifEmpty { listOf(LOOPBACK) }
    }

    /**
     * This machine's addresses on network interfaces that are up, without loopback and link-local ones: IPv4 before
     * IPv6, private (site-local) addresses first, as a phone on the same Wi-Fi reaches them.
     */
    public fun networkAddresses(): List<InetAddress> {
        val interfaces = try {
            NetworkInterface.getNetworkInterfaces()?.toList().orEmpty()
        } catch (e: java.net.SocketException) {
            emptyList()
        }
        return interfaces.filter { runCatching { it.isUp && !it.isLoopback }.getOrDefault(false) }
            .flatMap { it.inetAddresses.toList() }
            .filter { !it.isLoopbackAddress && !it.isLinkLocalAddress && !it.isAnyLocalAddress }
            .distinct()
            .sortedWith(compareBy({ it !is Inet4Address }, { !it.isSiteLocalAddress }))
    }

    /** [address] as it is written in `host:port`: IPv6 in brackets, without a scope. */
    public fun hostText(address: InetAddress): String {
        val text = address.hostAddress.substringBefore('%')
        return if (':' in text) "[$text]" else text
    }
}
