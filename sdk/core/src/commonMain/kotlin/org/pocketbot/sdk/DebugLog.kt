package org.pocketbot.sdk

import kotlinx.coroutines.channels.BufferOverflow
import kotlinx.coroutines.flow.MutableSharedFlow
import kotlinx.coroutines.flow.SharedFlow
import kotlinx.coroutines.flow.asSharedFlow
import org.pocketbot.protocol.DebugText

/** Where a [DebugMessage] comes from. */
public enum class DebugSource {
    /** A firmware module sent it as `debug_text` (its verbosity is settings.debug.level). */
    ROBOT,

    /** The SDK itself, about this robot's link: dropped frames, losses, reconnects. */
    HOST,
}

/**
 * One debug message.
 *
 * @property module the firmware module for [DebugSource.ROBOT] messages, null for the SDK's own.
 * @property level 1 errors, 2 info, 3 verbose, 4 trace.
 */
public class DebugMessage internal constructor(
    public val source: DebugSource,
    public val module: DebugModule?,
    public val level: Int,
    public val text: String,
) {
    override fun equals(other: Any?): Boolean =
        other is DebugMessage && source == other.source && module == other.module && level == other.level && text == other.text

    override fun hashCode(): Int = listOf(source, module, level, text).hashCode()

    override fun toString(): String = "[${module?.name?.lowercase() ?: source.name.lowercase()}:$level] $text"
}

/** The robot's debug log (thesis 6.2.3) and the SDK's warnings about the link, as one hot flow. */
public class DebugLog internal constructor() {
    private val _messages = MutableSharedFlow<DebugMessage>(
        replay = 32, extraBufferCapacity = 224, onBufferOverflow = BufferOverflow.DROP_OLDEST,
    )

    /** Messages as they arrive; a new collector first gets the last 32. Never suspends the link. */
    public val messages: SharedFlow<DebugMessage> = _messages.asSharedFlow()

    internal fun robot(p: DebugText) {
        _messages.tryEmit(DebugMessage(DebugSource.ROBOT, DebugModule.fromCode(p.module).takeIf { it != DebugModule.UNKNOWN }, p.level, p.text.decodeToString()))
    }

    internal fun host(level: Int, text: String) {
        _messages.tryEmit(DebugMessage(DebugSource.HOST, null, level, text))
    }
}
