package org.pocketbot.emulator.link

import java.util.SplittableRandom

/**
 * Every host link of one robot: as many as its firmware serves at once (`sim_links`), each a [RobotLink] with the
 * same [LinkSettings] (one radio). A host that connects gets the lowest free link; with none free it is refused,
 * as a robot whose links are all in use refuses another Bluetooth connection.
 */
internal class RobotLinks(count: Int, seed: Long) {
    /** Link 0 is the robot's UART; its generator is the one a robot with a single link always had. */
    public val all: List<RobotLink> = List(count) { k -> RobotLink(k, SplittableRandom(if (k == 0) seed else seed * 31 + k)) }

    /** The link model of every link now. */
    public val settings: LinkSettings get() = all[0].settings

    internal fun applySettings(s: LinkSettings) = all.forEach { it.applySettings(s) }

    /**
     * Connects [c] to the lowest free link and returns it.
     * @throws NoFreeLinkException when every link carries a host; [IllegalStateException] when the link is down.
     */
    public fun attach(c: LinkConnection): RobotLink {
        if (!settings.connected) throw IllegalStateException("link is down")
        return all.firstOrNull { it.tryAttach(c) } ?: throw NoFreeLinkException(all.size)
    }

    /** How many links carry a host now. */
    public val attached: Int get() = all.count { it.isAttached }

    public val bytesToHost: Long get() = all.sumOf { it.bytesToHost }
    public val bytesLost: Long get() = all.sumOf { it.bytesLost }
    public val bytesCorrupted: Long get() = all.sumOf { it.bytesCorrupted }
    public val bytesOverflowed: Long get() = all.sumOf { it.bytesOverflowed }

    internal fun dropConnections(reason: String) = all.forEach { it.dropConnection(reason) }
}

/** Every one of the robot's [links] host links carries a host: another one gets none. */
public class NoFreeLinkException(public val links: Int) :
    IllegalStateException("all $links host links of the robot are in use by other hosts")
