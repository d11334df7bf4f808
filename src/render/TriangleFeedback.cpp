// Transform feedback of the tessellated triangles (TriangleFeedback.h).
#include "render/TriangleFeedback.h"

namespace terrain {

void TriangleFeedback::begin(std::uint64_t triangles)
{
    if (!mBuffer) {
        mBuffer = gl::Buffer::create();
    }
    mCapacity = triangles;
    mCaptured = 0;
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, mBuffer.name());
    glBufferData(GL_TRANSFORM_FEEDBACK_BUFFER, static_cast<GLsizeiptr>(triangles * 3 * sizeof(glm::vec3)), nullptr,
                 GL_STREAM_READ);
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, 0);
}

void TriangleFeedback::beginDraw()
{
    glBindBufferRange(GL_TRANSFORM_FEEDBACK_BUFFER, 0, mBuffer.name(),
                      static_cast<GLintptr>(mCaptured * 3 * sizeof(glm::vec3)),
                      static_cast<GLsizeiptr>((mCapacity - mCaptured) * 3 * sizeof(glm::vec3)));
    glGenQueries(1, &mWritten);
    glGenQueries(1, &mGenerated);
    glBeginQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, mWritten);
    glBeginQuery(GL_PRIMITIVES_GENERATED, mGenerated);
    glBeginTransformFeedback(GL_TRIANGLES);
}

void TriangleFeedback::endDraw(std::uint64_t& generated)
{
    glEndTransformFeedback();
    glEndQuery(GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN);
    glEndQuery(GL_PRIMITIVES_GENERATED);
    GLuint written = 0, made = 0;
    glGetQueryObjectuiv(mWritten, GL_QUERY_RESULT, &written);
    glGetQueryObjectuiv(mGenerated, GL_QUERY_RESULT, &made);
    glDeleteQueries(1, &mWritten);
    glDeleteQueries(1, &mGenerated);
    generated += made;
    glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, 0, 0);
    mCaptured += written;
}

void TriangleFeedback::read(std::vector<glm::vec3>& out)
{
    out.resize(mCaptured * 3);
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, mBuffer.name());
    glGetBufferSubData(GL_TRANSFORM_FEEDBACK_BUFFER, 0, static_cast<GLsizeiptr>(mCaptured * 3 * sizeof(glm::vec3)),
                       out.data());
    glBindBuffer(GL_TRANSFORM_FEEDBACK_BUFFER, 0);
}

}  // namespace terrain
