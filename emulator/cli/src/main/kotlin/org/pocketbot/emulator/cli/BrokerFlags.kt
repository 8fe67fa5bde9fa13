package org.pocketbot.emulator.cli

import com.github.ajalt.clikt.core.UsageError
import com.github.ajalt.clikt.parameters.groups.OptionGroup
import com.github.ajalt.clikt.parameters.options.flag
import com.github.ajalt.clikt.parameters.options.option
import com.github.ajalt.clikt.parameters.types.file
import org.pocketbot.sdk.mqtt.BrokerOptions

/**
 * How a command reaches an MQTT broker (robots of other hosts, behind their gateways): `--broker URL` and its
 * credentials. The password comes from a file or from `POCKETBOT_BROKER_PASSWORD`, never from the command line, where
 * every user of the machine reads it (`ps`). Shared by `make emulator` and the `pocketbot` command line.
 */
public class BrokerFlags : OptionGroup("Broker options (robots of other hosts, through an MQTT broker)") {
    public val url: String? by option("--broker", metavar = "URL", help = "the broker: mqtts://HOST[:8883] (TLS) or mqtt://HOST[:1883]")
    private val user by option("--user", metavar = "NAME", help = "the broker user (the ACL decides what it may read and write)")
    private val passwordFile by option("--password-file", metavar = "FILE",
        help = "the broker user's password, the file's first line (else \$${BrokerOptions.PASSWORD_VARIABLE})")
        .file(mustExist = true, canBeDir = false, mustBeReadable = true)
    private val ca by option("--ca", metavar = "FILE", help = "the CA certificate (PEM) the broker's TLS certificate is checked against (else the JVM's trust store)")
        .file(mustExist = true, canBeDir = false, mustBeReadable = true)
    private val watch by option("--watch-only", help = "the broker user may only watch robots (a watcher of the broker's ACL): ask for no drive").flag()

    /**
     * The broker as the options say, or null without `--broker`.
     *
     * @throws UsageError for credentials without a broker, or a URL that names none.
     */
    public fun options(): BrokerOptions? {
        val url = url ?: run {
            if (user != null || passwordFile != null || ca != null || watch) throw UsageError("--user, --password-file, --ca and --watch-only need --broker", "--broker")
            return null
        }
        return try {
            BrokerOptions(url) {
                username = user
                passwordFrom(passwordFile)
                watchOnly = watch
                trustedCertificates = ca
            }
        } catch (e: IllegalArgumentException) {
            throw UsageError("--broker wants mqtt://HOST[:PORT] or mqtts://HOST[:PORT]: ${e.message}", "--broker")
        }
    }
}
