package org.pocketbot.desktop.ui

import androidx.compose.ui.geometry.Size
import androidx.compose.ui.graphics.Color
import androidx.compose.ui.graphics.asComposeCanvas
import androidx.compose.ui.graphics.drawscope.CanvasDrawScope
import androidx.compose.ui.graphics.drawscope.DrawScope
import androidx.compose.ui.text.TextMeasurer
import androidx.compose.ui.text.font.createFontFamilyResolver
import androidx.compose.ui.unit.Density
import androidx.compose.ui.unit.LayoutDirection
import org.jetbrains.skia.EncodedImageFormat
import org.jetbrains.skia.Surface
import java.io.File

/** A text measurer for drawing off screen (PNG export), where no composition provides one. */
val offscreenTextMeasurer: TextMeasurer by lazy { TextMeasurer(createFontFamilyResolver(), Density(1f), LayoutDirection.Ltr) }

/** Draws [draw] on a white [width] x [height] picture, off screen, and writes it to [file] as PNG. */
fun exportPng(file: File, width: Int, height: Int, draw: DrawScope.() -> Unit) {
    val surface = Surface.makeRasterN32Premul(width, height)
    CanvasDrawScope().draw(Density(1f), LayoutDirection.Ltr, surface.canvas.asComposeCanvas(), Size(width.toFloat(), height.toFloat())) {
        drawRect(Color.White)
        draw()
    }
    val png = surface.makeImageSnapshot().encodeToData(EncodedImageFormat.PNG) ?: error("PNG encoding failed")
    file.writeBytes(png.bytes)
}
