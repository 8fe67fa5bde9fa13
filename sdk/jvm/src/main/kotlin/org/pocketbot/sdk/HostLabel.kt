package org.pocketbot.sdk

import java.io.File
import java.net.InetAddress

/** Labels by which this host is shown to the people at the other hosts of a robot ([RobotOptions.hostLabel]). */
public object HostLabel {
    /**
     * `<program>@<this computer's name>`, e.g. `panel@lab-pc` (the robot keeps its first 16 bytes): the computer's
     * name without its domain, from the environment, /etc/hostname or the network's idea of it, else `host`.
     */
    public fun of(program: String): String = "$program@${computer()}"

    private fun computer(): String {
        val name = System.getenv("HOSTNAME")?.takeIf { it.isNotBlank() }
            ?: runCatching { File("/etc/hostname").readText().trim() }.getOrNull()?.takeIf { it.isNotEmpty() }
            ?: runCatching { InetAddress.getLocalHost().hostName }.getOrNull()
            ?: "host"
        return name.substringBefore('.')
    }
}
