package org.pocketbot.sdk.transport

import java.io.File
import java.util.concurrent.TimeUnit
import org.freedesktop.dbus.connections.impl.DBusConnectionBuilder
import org.freedesktop.dbus.interfaces.DBus

/**
 * A private D-Bus daemon with python-dbusmock's BlueZ 5 template on it, for tests: a fake `bluetoothd` whose
 * adapters and devices the test adds. Needs `dbus-daemon` and Debian's `python3-dbusmock` (for /usr/bin/python3).
 */
class BluezMock(withBluez: Boolean = true) : AutoCloseable {
    private val daemon: Process = ProcessBuilder(
        "dbus-daemon", "--session", "--nofork", "--print-address=1", "--address=unix:tmpdir=/tmp",
    ).redirectError(ProcessBuilder.Redirect.DISCARD).start()
    val address: String = daemon.inputStream.bufferedReader().readLine()
        ?: error("dbus-daemon printed no address")
    private val log = File.createTempFile("dbusmock", ".log")
    private val mock: Process? = if (!withBluez) null else ProcessBuilder(
        PYTHON, "-m", "dbusmock", "--session", "--template", "bluez5",
    ).apply { environment()["DBUS_SESSION_BUS_ADDRESS"] = address }
        .redirectErrorStream(true).redirectOutput(log).start()

    init {
        if (mock != null) {
            val deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(20)
            DBusConnectionBuilder.forAddress(address).withShared(false).build().use { c ->
                val bus = c.getRemoteObject("org.freedesktop.DBus", "/org/freedesktop/DBus", DBus::class.java)
                while (!bus.NameHasOwner("org.bluez")) {
                    check(mock.isAlive) { "dbusmock ended: ${log.readText()}" }
                    check(System.nanoTime() < deadline) { "dbusmock did not take org.bluez within 20 s: ${log.readText()}" }
                    Thread.sleep(50)
                }
            }
        }
    }

    fun addAdapter(name: String) = py("m.AddAdapter('$name', 'pocketbot-test-host')")

    fun addDevice(adapter: String, address: String, alias: String, uuids: List<String> = emptyList()) {
        py("p = m.AddDevice('$adapter', '$address', '$alias')")
        if (uuids.isNotEmpty()) {
            val list = uuids.joinToString(",") { "'$it'" }
            updateDevice(adapter, address, "'UUIDs': dbus.Array([$list], signature='s')")
        }
    }

    /** Changes Device1 properties (a Python dict body) and emits PropertiesChanged, as bluetoothd does. */
    fun updateDevice(adapter: String, address: String, properties: String) {
        val path = "/org/bluez/$adapter/dev_" + address.replace(':', '_')
        py("dbus.Interface(b.get_object('org.bluez', '$path'), 'org.freedesktop.DBus.Mock')" +
            ".UpdateProperties('org.bluez.Device1', {$properties})")
    }

    fun isDiscovering(adapter: String): Boolean =
        py("print(bool(dbus.Interface(b.get_object('org.bluez', '/org/bluez/$adapter'), " +
            "'org.freedesktop.DBus.Properties').Get('org.bluez.Adapter1', 'Discovering')))").trim() == "True"

    /** Runs Python with `dbus`, `b` (the bus) and `m` (the BlueZ mock interface) defined; returns its output. */
    private fun py(code: String): String {
        val script = "import dbus\nb = dbus.bus.BusConnection('$address')\n" +
            "m = dbus.Interface(b.get_object('org.bluez', '/'), 'org.bluez.Mock')\n$code\n"
        val p = ProcessBuilder(PYTHON, "-c", script).redirectErrorStream(true).start()
        val out = p.inputStream.bufferedReader().readText()
        check(p.waitFor(20, TimeUnit.SECONDS) && p.exitValue() == 0) { "python failed: $out" }
        return out
    }

    override fun close() {
        mock?.destroy()
        mock?.waitFor(5, TimeUnit.SECONDS)
        daemon.destroy()
        daemon.waitFor(5, TimeUnit.SECONDS)
        log.delete()
    }

    companion object {
        /** Debian's python, where python3-dbusmock is installed (a pyenv python on PATH may lack it). */
        const val PYTHON = "/usr/bin/python3"

        val available: Boolean by lazy {
            runCatching {
                ProcessBuilder("dbus-daemon", "--version").start().waitFor() == 0 &&
                    ProcessBuilder(PYTHON, "-c", "import dbusmock.templates.bluez5").start().waitFor() == 0
            }.getOrDefault(false)
        }
    }
}
