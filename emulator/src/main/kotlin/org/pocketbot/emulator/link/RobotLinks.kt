package org.pocketbot.emulator.link

import java.util.SplittableRandom

/**
 * Every host link of one robot: as many as its firmware serves at once (`sim_links`), each a [RobotLink] with the
 * same [LinkSettings] (one radio). A host that connects gets the lowest free link; with none free it is refused,
 * as a robot whose links are all in use refuses another Bluetooth connection.
 */
internal class RobotLinks(count: Int, seed: Long) {
    /** Link 0 is the robot's UART; its generator is the one a robot with a single link always had. */
    val all: List<RobotLink> = List(count) { k -> RobotLink(k, SplittableRandom(if (k == 0) seed else seed * 31 + k)) }

    /** The link model of every link now. */
    val settings: LinkSettings get() = all[0].settings

    fun applySettings(s: LinkSettings) = all.forEach { it.applySettings(s) }

    /**
     * Connects [c] to the lowest free link and returns it.
     * @throws NoFreeLinkException when every link carries a host; [IllegalStateException] when the link is down.
     */
    fun attach(c: LinkConnection): RobotLink {
        if (!settings.connected) throw IllegalStateException("link is down")
        return all.firstOrNull { it.tryAttach(c) } ?: throw NoFreeLinkException(all.size)
    }

    /** How many links carry a host now. */
    val attached: Int get() = all.count { it.isAttached }

    val bytesToHost: Long get() = all.sumOf { it.bytesToHost }
    val bytesLost: Long get() = all.sumOf { it.bytesLost }
    val bytesCorrupted: Long get() = all.sumOf { it.bytesCorrupted }
    val bytesOverflowed: Long get() = all.sumOf { it.bytesOverflowed }

    fun dropConnections(reason: String) = all.forEach { it.dropConnection(reason) }
}

/** Every one of the robot's [links] host links carries a host: another one gets none. */
internal class NoFreeLinkException(val links: Int) :
    IllegalStateException("all $links host links of the robot are in use by other hosts")
