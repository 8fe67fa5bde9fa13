package org.pocketbot.sdk.transport

import java.io.File

/**
 * The RFCOMM ttys bound on this Linux machine (`rfcomm bind`), read from sysfs: the kernel lists each bound
 * `/dev/rfcommN` as `/sys/class/tty/rfcommN/address` (the remote Bluetooth address). No root needed.
 */
public object RfcommTtys {
    /**
     * Bluetooth address (upper case, `00:11:22:33:44:55`) to tty path (`/dev/rfcomm0`) for every bound RFCOMM
     * tty; empty where there are none, or no sysfs (not Linux). Reads the files each time it is called.
     *
     * @param sysClassTty the sysfs folder to read, for tests.
     */
    public fun bound(sysClassTty: File = File("/sys/class/tty")): Map<String, String> {
        val ttys = sysClassTty.listFiles { f -> f.name.startsWith("rfcomm") } ?: return emptyMap()
        return ttys.sortedBy { it.name }.mapNotNull { tty ->
            val address = runCatching { File(tty, "address").readText().trim().uppercase() }.getOrNull()
            if (address.isNullOrEmpty() || address == "00:00:00:00:00:00") null else address to "/dev/${tty.name}"
        }.toMap()
    }
}
